from http import HTTPStatus
from typing import Any, cast
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response, UNSET
from ... import errors

from ...models.problem import Problem
from ...models.session_create import SessionCreate
from ...models.session_out import SessionOut
from ...types import UNSET, Unset
from typing import cast



def _get_kwargs(
    *,
    body: SessionCreate,
    limit: int | None | Unset = UNSET,
    idempotency_key: None | str | Unset = UNSET,

) -> dict[str, Any]:
    headers: dict[str, Any] = {}
    if not isinstance(idempotency_key, Unset):
        headers["Idempotency-Key"] = idempotency_key



    

    params: dict[str, Any] = {}

    json_limit: int | None | Unset
    if isinstance(limit, Unset):
        json_limit = UNSET
    else:
        json_limit = limit
    params["limit"] = json_limit


    params = {k: v for k, v in params.items() if v is not UNSET and v is not None}


    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/sessions",
        "params": params,
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs



def _parse_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> Problem | SessionOut | None:
    if response.status_code == 201:
        response_201 = SessionOut.from_dict(response.json())



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


def _build_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> Response[Problem | SessionOut]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    *,
    client: AuthenticatedClient | Client,
    body: SessionCreate,
    limit: int | None | Unset = UNSET,
    idempotency_key: None | str | Unset = UNSET,

) -> Response[Problem | SessionOut]:
    """ Create Session

     Start a recognition over an object set (registered names or inline §8 objects).
    The session belongs to the client whose key created it: other keys get 404.

    Args:
        limit (int | None | Unset): at most this many hypotheses
        idempotency_key (None | str | Unset): replays the first answer to a retried request (other
            body: 422)
        body (SessionCreate): A new session: its object set (registered names or inline §8
            objects), sensor
            bounds, safe circle, the sensor's place on it, strategy and allowed outliers.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | SessionOut]
     """


    kwargs = _get_kwargs(
        body=body,
limit=limit,
idempotency_key=idempotency_key,

    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)

def sync(
    *,
    client: AuthenticatedClient | Client,
    body: SessionCreate,
    limit: int | None | Unset = UNSET,
    idempotency_key: None | str | Unset = UNSET,

) -> Problem | SessionOut | None:
    """ Create Session

     Start a recognition over an object set (registered names or inline §8 objects).
    The session belongs to the client whose key created it: other keys get 404.

    Args:
        limit (int | None | Unset): at most this many hypotheses
        idempotency_key (None | str | Unset): replays the first answer to a retried request (other
            body: 422)
        body (SessionCreate): A new session: its object set (registered names or inline §8
            objects), sensor
            bounds, safe circle, the sensor's place on it, strategy and allowed outliers.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | SessionOut
     """


    return sync_detailed(
        client=client,
body=body,
limit=limit,
idempotency_key=idempotency_key,

    ).parsed

async def asyncio_detailed(
    *,
    client: AuthenticatedClient | Client,
    body: SessionCreate,
    limit: int | None | Unset = UNSET,
    idempotency_key: None | str | Unset = UNSET,

) -> Response[Problem | SessionOut]:
    """ Create Session

     Start a recognition over an object set (registered names or inline §8 objects).
    The session belongs to the client whose key created it: other keys get 404.

    Args:
        limit (int | None | Unset): at most this many hypotheses
        idempotency_key (None | str | Unset): replays the first answer to a retried request (other
            body: 422)
        body (SessionCreate): A new session: its object set (registered names or inline §8
            objects), sensor
            bounds, safe circle, the sensor's place on it, strategy and allowed outliers.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | SessionOut]
     """


    kwargs = _get_kwargs(
        body=body,
limit=limit,
idempotency_key=idempotency_key,

    )

    response = await client.get_async_httpx_client().request(
        **kwargs
    )

    return _build_response(client=client, response=response)

async def asyncio(
    *,
    client: AuthenticatedClient | Client,
    body: SessionCreate,
    limit: int | None | Unset = UNSET,
    idempotency_key: None | str | Unset = UNSET,

) -> Problem | SessionOut | None:
    """ Create Session

     Start a recognition over an object set (registered names or inline §8 objects).
    The session belongs to the client whose key created it: other keys get 404.

    Args:
        limit (int | None | Unset): at most this many hypotheses
        idempotency_key (None | str | Unset): replays the first answer to a retried request (other
            body: 422)
        body (SessionCreate): A new session: its object set (registered names or inline §8
            objects), sensor
            bounds, safe circle, the sensor's place on it, strategy and allowed outliers.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | SessionOut
     """


    return (await asyncio_detailed(
        client=client,
body=body,
limit=limit,
idempotency_key=idempotency_key,

    )).parsed
