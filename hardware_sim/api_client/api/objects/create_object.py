from http import HTTPStatus
from typing import Any, cast
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response, UNSET
from ... import errors

from ...models.object_created import ObjectCreated
from ...models.object_in import ObjectIn
from ...models.problem import Problem
from typing import cast



def _get_kwargs(
    *,
    body: ObjectIn,

) -> dict[str, Any]:
    headers: dict[str, Any] = {}


    

    

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/objects",
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs



def _parse_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> ObjectCreated | Problem | None:
    if response.status_code == 200:
        response_200 = ObjectCreated.from_dict(response.json())



        return response_200

    if response.status_code == 201:
        response_201 = ObjectCreated.from_dict(response.json())



        return response_201

    if response.status_code == 400:
        response_400 = Problem.from_dict(response.json())



        return response_400

    if response.status_code == 401:
        response_401 = Problem.from_dict(response.json())



        return response_401

    if response.status_code == 404:
        response_404 = Problem.from_dict(response.json())



        return response_404

    if response.status_code == 409:
        response_409 = Problem.from_dict(response.json())



        return response_409

    if response.status_code == 412:
        response_412 = Problem.from_dict(response.json())



        return response_412

    if response.status_code == 413:
        response_413 = Problem.from_dict(response.json())



        return response_413

    if response.status_code == 422:
        response_422 = Problem.from_dict(response.json())



        return response_422

    if response.status_code == 503:
        response_503 = Problem.from_dict(response.json())



        return response_503

    if client.raise_on_unexpected_status:
        raise errors.UnexpectedStatus(response.status_code, response.content)
    else:
        return None


def _build_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> Response[ObjectCreated | Problem]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    *,
    client: AuthenticatedClient | Client,
    body: ObjectIn,

) -> Response[ObjectCreated | Problem]:
    """ Create Object

     Register one object (§8 format). The same name with other geometry: 409.
    Objects are named per client: another key's objects are not seen.

    Args:
        body (ObjectIn): One object in the §8 format: `outline` (one stable pose) or
            `stable_poses`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[ObjectCreated | Problem]
     """


    kwargs = _get_kwargs(
        body=body,

    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)

def sync(
    *,
    client: AuthenticatedClient | Client,
    body: ObjectIn,

) -> ObjectCreated | Problem | None:
    """ Create Object

     Register one object (§8 format). The same name with other geometry: 409.
    Objects are named per client: another key's objects are not seen.

    Args:
        body (ObjectIn): One object in the §8 format: `outline` (one stable pose) or
            `stable_poses`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        ObjectCreated | Problem
     """


    return sync_detailed(
        client=client,
body=body,

    ).parsed

async def asyncio_detailed(
    *,
    client: AuthenticatedClient | Client,
    body: ObjectIn,

) -> Response[ObjectCreated | Problem]:
    """ Create Object

     Register one object (§8 format). The same name with other geometry: 409.
    Objects are named per client: another key's objects are not seen.

    Args:
        body (ObjectIn): One object in the §8 format: `outline` (one stable pose) or
            `stable_poses`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[ObjectCreated | Problem]
     """


    kwargs = _get_kwargs(
        body=body,

    )

    response = await client.get_async_httpx_client().request(
        **kwargs
    )

    return _build_response(client=client, response=response)

async def asyncio(
    *,
    client: AuthenticatedClient | Client,
    body: ObjectIn,

) -> ObjectCreated | Problem | None:
    """ Create Object

     Register one object (§8 format). The same name with other geometry: 409.
    Objects are named per client: another key's objects are not seen.

    Args:
        body (ObjectIn): One object in the §8 format: `outline` (one stable pose) or
            `stable_poses`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        ObjectCreated | Problem
     """


    return (await asyncio_detailed(
        client=client,
body=body,

    )).parsed
