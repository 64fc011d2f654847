from http import HTTPStatus
from typing import Any, cast
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response, UNSET
from ... import errors

from ...models.plan_out import PlanOut
from ...models.problem import Problem
from ...types import UNSET, Unset
from typing import cast
from uuid import UUID



def _get_kwargs(
    session_id: UUID,
    *,
    limit: int | Unset = 5,
    sensor_x: float | None | Unset = UNSET,
    sensor_y: float | None | Unset = UNSET,

) -> dict[str, Any]:
    

    

    params: dict[str, Any] = {}

    params["limit"] = limit

    json_sensor_x: float | None | Unset
    if isinstance(sensor_x, Unset):
        json_sensor_x = UNSET
    else:
        json_sensor_x = sensor_x
    params["sensor_x"] = json_sensor_x

    json_sensor_y: float | None | Unset
    if isinstance(sensor_y, Unset):
        json_sensor_y = UNSET
    else:
        json_sensor_y = sensor_y
    params["sensor_y"] = json_sensor_y


    params = {k: v for k, v in params.items() if v is not UNSET and v is not None}


    _kwargs: dict[str, Any] = {
        "method": "get",
        "url": "/v1/sessions/{session_id}/plan".format(session_id=quote(str(session_id), safe=""),),
        "params": params,
    }


    return _kwargs



def _parse_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> PlanOut | Problem | None:
    if response.status_code == 200:
        response_200 = PlanOut.from_dict(response.json())



        return response_200

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


def _build_response(*, client: AuthenticatedClient | Client, response: httpx.Response) -> Response[PlanOut | Problem]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    session_id: UUID,
    *,
    client: AuthenticatedClient | Client,
    limit: int | Unset = 5,
    sensor_x: float | None | Unset = UNSET,
    sensor_y: float | None | Unset = UNSET,

) -> Response[PlanOut | Problem]:
    """ Get Plan

     Ranked sensing paths, best first, within the session's `budget_ms`
    (`truncated` says the search stopped early). With no contact yet: the opening probe.
    `sensor_x`, `sensor_y`: plan from where the sensor is now (motion costs and the
    opening probe start there); one alone moves the session's sensor_position along
    that axis.

    Args:
        session_id (UUID): session id (a random UUID)
        limit (int | Unset):  Default: 5.
        sensor_x (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's
        sensor_y (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[PlanOut | Problem]
     """


    kwargs = _get_kwargs(
        session_id=session_id,
limit=limit,
sensor_x=sensor_x,
sensor_y=sensor_y,

    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)

def sync(
    session_id: UUID,
    *,
    client: AuthenticatedClient | Client,
    limit: int | Unset = 5,
    sensor_x: float | None | Unset = UNSET,
    sensor_y: float | None | Unset = UNSET,

) -> PlanOut | Problem | None:
    """ Get Plan

     Ranked sensing paths, best first, within the session's `budget_ms`
    (`truncated` says the search stopped early). With no contact yet: the opening probe.
    `sensor_x`, `sensor_y`: plan from where the sensor is now (motion costs and the
    opening probe start there); one alone moves the session's sensor_position along
    that axis.

    Args:
        session_id (UUID): session id (a random UUID)
        limit (int | Unset):  Default: 5.
        sensor_x (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's
        sensor_y (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        PlanOut | Problem
     """


    return sync_detailed(
        session_id=session_id,
client=client,
limit=limit,
sensor_x=sensor_x,
sensor_y=sensor_y,

    ).parsed

async def asyncio_detailed(
    session_id: UUID,
    *,
    client: AuthenticatedClient | Client,
    limit: int | Unset = 5,
    sensor_x: float | None | Unset = UNSET,
    sensor_y: float | None | Unset = UNSET,

) -> Response[PlanOut | Problem]:
    """ Get Plan

     Ranked sensing paths, best first, within the session's `budget_ms`
    (`truncated` says the search stopped early). With no contact yet: the opening probe.
    `sensor_x`, `sensor_y`: plan from where the sensor is now (motion costs and the
    opening probe start there); one alone moves the session's sensor_position along
    that axis.

    Args:
        session_id (UUID): session id (a random UUID)
        limit (int | Unset):  Default: 5.
        sensor_x (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's
        sensor_y (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[PlanOut | Problem]
     """


    kwargs = _get_kwargs(
        session_id=session_id,
limit=limit,
sensor_x=sensor_x,
sensor_y=sensor_y,

    )

    response = await client.get_async_httpx_client().request(
        **kwargs
    )

    return _build_response(client=client, response=response)

async def asyncio(
    session_id: UUID,
    *,
    client: AuthenticatedClient | Client,
    limit: int | Unset = 5,
    sensor_x: float | None | Unset = UNSET,
    sensor_y: float | None | Unset = UNSET,

) -> PlanOut | Problem | None:
    """ Get Plan

     Ranked sensing paths, best first, within the session's `budget_ms`
    (`truncated` says the search stopped early). With no contact yet: the opening probe.
    `sensor_x`, `sensor_y`: plan from where the sensor is now (motion costs and the
    opening probe start there); one alone moves the session's sensor_position along
    that axis.

    Args:
        session_id (UUID): session id (a random UUID)
        limit (int | Unset):  Default: 5.
        sensor_x (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's
        sensor_y (float | None | Unset): the sensor's current place (world frame); a coordinate
            not given is the session's sensor_position's

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        PlanOut | Problem
     """


    return (await asyncio_detailed(
        session_id=session_id,
client=client,
limit=limit,
sensor_x=sensor_x,
sensor_y=sensor_y,

    )).parsed
