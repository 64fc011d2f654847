from http import HTTPStatus
from typing import Any, cast
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response, UNSET
from ... import errors

from ...models.import_mesh_file_type import ImportMeshFileType
from ...models.object_created import ObjectCreated
from ...models.problem import Problem
from ...types import File, FileTypes
from ...types import UNSET, Unset
from io import BytesIO
from typing import cast



def _get_kwargs(
    *,
    body: File,
    height: float,
    name: str,
    file_type: ImportMeshFileType | Unset = ImportMeshFileType.STL,
    max_poses: int | None | Unset = UNSET,
    heights: list[float] | None | Unset = UNSET,

) -> dict[str, Any]:
    headers: dict[str, Any] = {}


    

    params: dict[str, Any] = {}

    params["height"] = height

    params["name"] = name

    json_file_type: str | Unset = UNSET
    if not isinstance(file_type, Unset):
        json_file_type = file_type.value

    params["file_type"] = json_file_type

    json_max_poses: int | None | Unset
    if isinstance(max_poses, Unset):
        json_max_poses = UNSET
    else:
        json_max_poses = max_poses
    params["max_poses"] = json_max_poses

    json_heights: list[float] | None | Unset
    if isinstance(heights, Unset):
        json_heights = UNSET
    elif isinstance(heights, list):
        json_heights = heights


    else:
        json_heights = heights
    params["heights"] = json_heights


    params = {k: v for k, v in params.items() if v is not UNSET and v is not None}


    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/objects:import-mesh",
        "params": params,
    }

    _kwargs["content"] = body.payload
    headers["Content-Type"] = "application/octet-stream"

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

    if response.status_code == 415:
        response_415 = Problem.from_dict(response.json())



        return response_415

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
    body: File,
    height: float,
    name: str,
    file_type: ImportMeshFileType | Unset = ImportMeshFileType.STL,
    max_poses: int | None | Unset = UNSET,
    heights: list[float] | None | Unset = UNSET,

) -> Response[ObjectCreated | Problem]:
    """ Import Mesh

     Register a 3-D part from its triangle mesh (the request body, at most the body
    limit): stable poses with their probabilities, each sliced at `height` into an
    outline (and at each of `heights`: slices at several probing heights, the
    planner then chooses the height of each path), faces carrying their out-of-plane
    normal. Same name, other geometry: 409.
    Content-Type application/octet-stream (or model/*, application/sla,
    application/vnd.ms-pki.stl); any other: 415.

    Args:
        height (float): slice height above the table
        name (str):
        file_type (ImportMeshFileType | Unset):  Default: ImportMeshFileType.STL.
        max_poses (int | None | Unset):
        heights (list[float] | None | Unset): more probing heights: each stable pose is also
            sliced there (at most max_slices heights in all, `height` included)
        body (File):

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[ObjectCreated | Problem]
     """


    kwargs = _get_kwargs(
        body=body,
height=height,
name=name,
file_type=file_type,
max_poses=max_poses,
heights=heights,

    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)

def sync(
    *,
    client: AuthenticatedClient | Client,
    body: File,
    height: float,
    name: str,
    file_type: ImportMeshFileType | Unset = ImportMeshFileType.STL,
    max_poses: int | None | Unset = UNSET,
    heights: list[float] | None | Unset = UNSET,

) -> ObjectCreated | Problem | None:
    """ Import Mesh

     Register a 3-D part from its triangle mesh (the request body, at most the body
    limit): stable poses with their probabilities, each sliced at `height` into an
    outline (and at each of `heights`: slices at several probing heights, the
    planner then chooses the height of each path), faces carrying their out-of-plane
    normal. Same name, other geometry: 409.
    Content-Type application/octet-stream (or model/*, application/sla,
    application/vnd.ms-pki.stl); any other: 415.

    Args:
        height (float): slice height above the table
        name (str):
        file_type (ImportMeshFileType | Unset):  Default: ImportMeshFileType.STL.
        max_poses (int | None | Unset):
        heights (list[float] | None | Unset): more probing heights: each stable pose is also
            sliced there (at most max_slices heights in all, `height` included)
        body (File):

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        ObjectCreated | Problem
     """


    return sync_detailed(
        client=client,
body=body,
height=height,
name=name,
file_type=file_type,
max_poses=max_poses,
heights=heights,

    ).parsed

async def asyncio_detailed(
    *,
    client: AuthenticatedClient | Client,
    body: File,
    height: float,
    name: str,
    file_type: ImportMeshFileType | Unset = ImportMeshFileType.STL,
    max_poses: int | None | Unset = UNSET,
    heights: list[float] | None | Unset = UNSET,

) -> Response[ObjectCreated | Problem]:
    """ Import Mesh

     Register a 3-D part from its triangle mesh (the request body, at most the body
    limit): stable poses with their probabilities, each sliced at `height` into an
    outline (and at each of `heights`: slices at several probing heights, the
    planner then chooses the height of each path), faces carrying their out-of-plane
    normal. Same name, other geometry: 409.
    Content-Type application/octet-stream (or model/*, application/sla,
    application/vnd.ms-pki.stl); any other: 415.

    Args:
        height (float): slice height above the table
        name (str):
        file_type (ImportMeshFileType | Unset):  Default: ImportMeshFileType.STL.
        max_poses (int | None | Unset):
        heights (list[float] | None | Unset): more probing heights: each stable pose is also
            sliced there (at most max_slices heights in all, `height` included)
        body (File):

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[ObjectCreated | Problem]
     """


    kwargs = _get_kwargs(
        body=body,
height=height,
name=name,
file_type=file_type,
max_poses=max_poses,
heights=heights,

    )

    response = await client.get_async_httpx_client().request(
        **kwargs
    )

    return _build_response(client=client, response=response)

async def asyncio(
    *,
    client: AuthenticatedClient | Client,
    body: File,
    height: float,
    name: str,
    file_type: ImportMeshFileType | Unset = ImportMeshFileType.STL,
    max_poses: int | None | Unset = UNSET,
    heights: list[float] | None | Unset = UNSET,

) -> ObjectCreated | Problem | None:
    """ Import Mesh

     Register a 3-D part from its triangle mesh (the request body, at most the body
    limit): stable poses with their probabilities, each sliced at `height` into an
    outline (and at each of `heights`: slices at several probing heights, the
    planner then chooses the height of each path), faces carrying their out-of-plane
    normal. Same name, other geometry: 409.
    Content-Type application/octet-stream (or model/*, application/sla,
    application/vnd.ms-pki.stl); any other: 415.

    Args:
        height (float): slice height above the table
        name (str):
        file_type (ImportMeshFileType | Unset):  Default: ImportMeshFileType.STL.
        max_poses (int | None | Unset):
        heights (list[float] | None | Unset): more probing heights: each stable pose is also
            sliced there (at most max_slices heights in all, `height` included)
        body (File):

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        ObjectCreated | Problem
     """


    return (await asyncio_detailed(
        client=client,
body=body,
height=height,
name=name,
file_type=file_type,
max_poses=max_poses,
heights=heights,

    )).parsed
