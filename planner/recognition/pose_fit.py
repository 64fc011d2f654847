"""Pose fit, Kalman refinement and error bounds (DESIGN §4.4).

The fit works in a lifted linear form. With ``m = R(theta)^T p + b`` the model
point of world point p (so ``b = -R^T t``), and the state ``z = (c, s, bx, by)``
standing for ``(cos theta, sin theta, b)``, every contact j on face a gives three
equations that are LINEAR in z:

- point on the face's line:  ``n_a·(R^T p_j + b) = d_a``
- normal, tangential part:   ``t_a·(R^T u_j) = 0``   (t_a = n_a turned +90 degrees)
- normal, radial part:       ``n_a·(R^T u_j) = 1``

so the weighted least-squares fit over all contacts (batch) and one Kalman update
per contact (incremental, :class:`PoseFilter`) agree to rounding. theta is
``atan2(s, c)`` (for one contact and equal weights, the circular mean of
``angle(u_j) - angle(n_a)``), and ``t = -R b / |(c, s)|``.

Error bounds (`linearized` mode): the first-order sensitivity of the fit to each
contact's position (a disk of radius eps_d) and normal angle (within ±phi),
summed in absolute value (worst case), gives |dt|, |dtheta| and the error-disk
diameter ``eps_t = 2 (|dq| + r |dtheta|)`` for a reference point q at the
outline's centroid and r the centroid's farthest vertex. A second-order
allowance covers the linearization.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from planner.compiled import c_array
from planner.geometry import SHARE_SLACK, rotate, rotation_matrices

__all__ = ["FitBatch", "PoseFilter", "fit_batch", "lifted_rows", "noise_scales"]

_J = np.array([[0.0, -1.0], [1.0, 0.0]])  # +90 degree turn


def noise_scales(eps_d: float, phi: float, length_scale: float) -> tuple[float, float]:
    """Standard scales (sigma_d, sigma_phi) weighting the rows; zero bounds get floors
    that keep the rows well conditioned (exact data fit exactly whatever the weights)."""
    if phi > 0 and eps_d > 0:
        return eps_d, phi
    if phi > 0:
        return 1e-3 * phi * length_scale, phi
    if eps_d > 0:
        return eps_d, 1e-3 * eps_d / length_scale
    return length_scale, 1.0


def lifted_rows(
    points: np.ndarray, normals: np.ndarray, face_normals: np.ndarray, face_offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Rows H (..., 3, 4) and targets y (..., 3) of the lifted contact equations.

    `points`, `normals` (measured, world) and `face_normals` (model) are (..., 2),
    `face_offsets` (...): broadcast over interpretations and contacts.
    """
    nx, ny = np.broadcast_arrays(face_normals[..., 0], face_normals[..., 1])
    px, py = points[..., 0], points[..., 1]
    ux, uy = normals[..., 0], normals[..., 1]
    # filled in place: the same products and sums as stacking the rows, without the stacks
    H = np.empty((*nx.shape, 3, 4))
    # n_a·(R^T p + b) = c (n·p) + s (nx py - ny px) + n·b
    H[..., 0, 0] = nx * px + ny * py
    H[..., 0, 1] = nx * py - ny * px
    H[..., 0, 2] = nx
    H[..., 0, 3] = ny
    # R^T u = (c ux + s uy, c uy - s ux): tangential -ny (ux, uy) + nx (uy, -ux), radial
    # nx (ux, uy) + ny (uy, -ux), nothing on b (each product with zero kept, for its sign)
    H[..., 1, 0] = -ny * ux + nx * uy
    H[..., 1, 1] = -ny * uy + nx * -ux
    H[..., 1, 2:] = (-ny * 0.0 + nx * 0.0)[..., None]
    H[..., 2, 0] = nx * ux + ny * uy
    H[..., 2, 1] = nx * uy + ny * -ux
    H[..., 2, 2:] = (nx * 0.0 + ny * 0.0)[..., None]
    y = np.empty((*nx.shape, 3))
    y[..., 0] = face_offsets
    y[..., 1] = 0.0
    y[..., 2] = 1.0
    return H, y


def _row_derivatives(z: np.ndarray, normals: np.ndarray, face_normals: np.ndarray) -> np.ndarray:
    """E (..., 3 rows, 3 measurements): d(H z)/d(px, py, psi) for each contact."""
    c, s = z[..., 0], z[..., 1]
    nx, ny = face_normals[..., 0], face_normals[..., 1]
    ux, uy = normals[..., 0], normals[..., 1]
    E = np.zeros((*np.broadcast_shapes(nx.shape, c.shape), 3, 3))
    # line row: d/dp [c (n·p) + s (nx py - ny px)]
    E[..., 0, 0] = c * nx - s * ny
    E[..., 0, 1] = c * ny + s * nx
    # normal rows: du/dpsi = (-uy, ux)
    d1 = -c * uy + s * ux
    d2 = c * ux + s * uy
    E[..., 1, 2] = -ny * d1 + nx * d2
    E[..., 2, 2] = nx * d1 + ny * d2
    return E


@dataclass(frozen=True, eq=False)
class FitBatch:
    """Fits of K interpretations. Arrays have leading axis K.

    `theta`, `t` (K, 2): the pose; `rank2`: translation fully determined (else a
    one-parameter family sliding along `slide` (K, 2, world, per unit of the model
    slide coordinate)); `sens` (K, s, 3, 3): d(qx, qy, theta)/d(px, py, psi) per
    contact with q the world position of `reference` (model point);
    `sens_origin` (K, s, 2, 3): the same for the pose translation;
    `cov` (K, 3, 3) covariance of (x, y, theta) at the row weights (rank-1 fits pinned
    along the slide at sigma_d; its determinant does not depend on the model origin);
    `chi2` (K,) weighted residual; `z` (K, 4) lifted state.
    """

    theta: np.ndarray
    t: np.ndarray
    rank2: np.ndarray
    slide: np.ndarray
    sens: np.ndarray
    sens_origin: np.ndarray
    cov: np.ndarray
    chi2: np.ndarray
    z: np.ndarray


def fit_batch(
    points: np.ndarray,
    normals: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    assigned: np.ndarray,
    reference: np.ndarray,
    sigma_d: float,
    sigma_phi: float,
) -> FitBatch:
    """Weighted least-squares pose of K interpretations over s contacts at once.

    `points`, `normals`: (s, 2) measured contacts (world), shared by every row, or
    (K, s, 2) per row; `face_normals` (K, s, 2)
    and `face_offsets` (K, s): the model faces assigned to them; `assigned` (K, s)
    bool (False = spurious contact, ignored); `reference` (K, 2) model point whose
    world position the bounds are expressed at. Every row needs one assigned contact.

    Rank-1 interpretations (all assigned faces parallel) are pinned at slide
    coordinate 0 along the face direction ``e`` in the model frame (``e·b = 0``);
    the caller moves them along `slide`.
    """
    K = assigned.shape[0]
    points = np.broadcast_to(points, (K, *points.shape[-2:]))
    normals = np.broadcast_to(normals, (K, *normals.shape[-2:]))
    rows = np.arange(K)
    H, y = lifted_rows(points, normals, face_normals, face_offsets)  # (K,s,3,4)
    w_row = np.array([1 / sigma_d**2, 1 / sigma_phi**2, 1 / sigma_phi**2])
    W = assigned[..., None] * w_row  # (K, s, 3)
    # products of two operands at a time (numpy's einsum of three or four operands
    # runs one loop over every index: ten times slower here)
    HW = H * W[..., None]  # (K, s, 3, 4)
    info = np.matmul(HW.reshape(K, -1, 4).transpose(0, 2, 1), H.reshape(K, -1, 4))
    vec = np.einsum("kri,kr->ki", HW.reshape(K, -1, 4), y.reshape(K, -1))

    # rank of the translation: do the assigned faces hold two non-parallel normals?
    first = np.argmax(assigned, axis=1)
    n_ref = face_normals[np.arange(K), first]  # (K, 2)
    cross = np.abs(
        n_ref[:, None, 0] * face_normals[..., 1] - n_ref[:, None, 1] * face_normals[..., 0]
    )
    rank2 = np.any(assigned & (cross > 1e-6), axis=1)
    # rank 1: pin the first contact's model coordinate along the faces, e·(R^T p_1 + b) = 0,
    # with e the face direction (model frame): samples then slide the object along the faces
    e = n_ref @ _J.T
    anchor = points[rows, first]  # (K, 2)
    pin, _ = lifted_rows(anchor, anchor, e, np.zeros(K))
    pin = pin[:, 0, :] * (~rank2)[:, None]  # the line-row form with n -> e
    info = info + np.einsum("ki,kj->kij", pin, pin) / sigma_d**2

    info_inv = np.linalg.inv(info)
    z = np.einsum("kij,kj->ki", info_inv, vec)
    c, s = z[:, 0], z[:, 1]
    rho2 = c * c + s * s
    rho = np.sqrt(rho2)
    theta = np.arctan2(s, c)
    R = rotation_matrices(theta)  # (K, 2, 2)
    b = z[:, 2:]
    Rb = np.einsum("kij,kj->ki", R, b)
    t = -Rb / rho[:, None]
    slide = -np.einsum("kij,kj->ki", R, e) / rho[:, None]

    # G = d(x, y, theta)/d(c, s, bx, by)
    G = np.zeros((K, 3, 4))
    G[:, 2, 0], G[:, 2, 1] = -s / rho2, c / rho2
    RJb = np.einsum("kij,kj->ki", R, b @ _J.T)
    for col, (dth, drho) in enumerate([(-s / rho2, c / rho), (c / rho2, s / rho)]):
        G[:, :2, col] = -RJb / rho[:, None] * dth[:, None] + Rb / rho2[:, None] * drho[:, None]
    G[:, :2, 2:] = -R / rho[:, None, None]

    # first order: dz = -info^-1 H^T W E dm  (residual terms are second order)
    E = _row_derivatives(z[:, None, :], normals, face_normals)  # (K, s, 3, 3)
    dz = -np.matmul(info_inv[:, None], np.matmul(HW.transpose(0, 1, 3, 2), E))
    # the pin's anchor is the first contact's measured point: its error moves the pin too
    e_pin = _row_derivatives(z, normals[rows, first], e)[:, 0, :2]  # (K, 2): d(pin·z)/d p_1
    dz_pin = -(info_inv @ pin[..., None]) * e_pin[:, None, :] / sigma_d**2
    dz[rows, first, :, :2] += dz_pin
    sens_origin = np.einsum("kij,ksjm->ksim", G, dz)  # (K, s, 3, 3)
    # q = R ref + t: dq = dt + R J ref dtheta
    arm = np.einsum("kij,kj->ki", R, reference @ _J.T)
    sens = sens_origin.copy()
    sens[:, :, :2, :] += arm[:, None, :, None] * sens_origin[:, :, None, 2, :]

    cov = _pose_covariance(R, t, slide, rank2, points, face_normals, assigned, sigma_d, sigma_phi)
    resid = y - np.einsum("ksri,ki->ksr", H, z)
    chi2 = np.einsum("ksr,ksr->k", W, resid**2)
    return FitBatch(
        theta=theta,
        t=t,
        rank2=rank2,
        slide=slide,
        sens=sens,
        sens_origin=sens_origin[:, :, :2, :],
        cov=cov,
        chi2=chi2,
        z=z,
    )


def _pose_covariance(
    R: np.ndarray,
    t: np.ndarray,
    slide: np.ndarray,
    rank2: np.ndarray,
    points: np.ndarray,
    face_normals: np.ndarray,
    assigned: np.ndarray,
    sigma_d: float,
    sigma_phi: float,
) -> np.ndarray:
    """Covariance (K, 3, 3) of the pose (x, y, theta) at the row weights.

    `R` (K, 2, 2), `t` (K, 2) the fitted poses, `slide` (K, 2) the world slide
    direction of rank-1 rows (`rank2` False), pinned along it at sigma_d; `points`
    (K, s, 2) the measured contacts (world), `face_normals` (K, s, 2) their model
    faces' normals, `assigned` (K, s) which contacts count.
    """
    K = assigned.shape[0]
    # pose-space information of the point-on-line and normal residuals:
    # line r = n_w·(p - t) - d:  dr/dt = -n_w,  dr/dtheta = (J n_w)·(p - t);  angle: dr/dtheta = -1
    n_w = np.einsum("kij,ksj->ksi", R, face_normals)
    lever = np.einsum("ksi,ksi->ks", n_w @ _J.T, points - t[:, None, :])
    g = np.concatenate([-n_w, lever[..., None]], axis=-1)  # (K, s, 3)
    info_pose = np.matmul((g * (assigned / sigma_d**2)[..., None]).transpose(0, 2, 1), g)
    info_pose[:, 2, 2] += assigned.sum(axis=1) / sigma_phi**2
    tau = slide / np.linalg.norm(slide, axis=1, keepdims=True)
    pin_pose = np.concatenate([tau, np.zeros((K, 1))], axis=1)
    info_pose += (~rank2)[:, None, None] * np.einsum("ki,kj->kij", pin_pose, pin_pose) / sigma_d**2
    return np.linalg.inv(info_pose)


def worst_rotation(sens: np.ndarray, assigned: np.ndarray, eps_d: float, phi: float) -> np.ndarray:
    """Worst-case |dtheta| (K,) from the sensitivities (first order).

    Each contact's position error lies in a disk of radius eps_d and its normal
    angle error within ±phi; the worst case adds every contribution in absolute
    value. (A point's worst move is :func:`point_bounds`'.)
    """
    dth = eps_d * np.hypot(sens[..., 2, 0], sens[..., 2, 1]) + phi * np.abs(sens[..., 2, 2])
    return (dth * assigned).sum(axis=1)


def point_bounds(
    fit: FitBatch,
    points: np.ndarray,
    assigned: np.ndarray,
    eps_d: float,
    phi: float,
    rows: np.ndarray | None = None,
) -> np.ndarray:
    """Worst-case first-order displacement (N, P) of model `points` in the world.

    `points` is (P, 2) for every fit or (N, P, 2) per fit; `rows` (N,) picks the fits
    (default: all K, in order).

    A model point v lands at ``R v + t``; its displacement under measurement errors is
    ``S_v = S_t + (R J v) S_theta`` per contact, and the worst case adds
    ``eps_d ||S_v[:, :2]|| + phi |S_v[:, 2]|`` over the contacts. Being affine in v,
    the displacement bound over a polygon is largest at a vertex.
    """
    rows = np.arange(len(fit.theta)) if rows is None else rows
    R = rotation_matrices(fit.theta[rows])
    points = np.broadcast_to(points, (len(rows), *points.shape[-2:]))
    arm = rotate(R @ _J, points)  # (N, P, 2): R J v
    out = np.empty(arm.shape[:2])
    _worst_moves(
        c_array(fit.sens_origin[rows], dtype=float),
        c_array(fit.sens[rows, :, 2, :], dtype=float),  # (N, s, 3): d theta / d(px, py, psi)
        arm,
        c_array(assigned[rows], dtype=bool),
        float(eps_d),
        float(phi),
        out,
    )
    return out


@numba.njit(cache=True, nogil=True)
def _worst_moves(sens_origin, s_theta, arm, assigned, eps_d, phi, out):  # type: ignore[no-untyped-def]
    """:func:`point_bounds` one fit and model point at a time: ``S_v = S_t + (R J
    v) S_theta`` per assigned contact, its 2x2 position block's spectral norm (in
    closed form) times eps_d plus phi times the norm of its normal column, summed
    over the contacts, without the (N, s, P, 2, 3) array."""
    N, S = assigned.shape
    for n in range(N):
        for p in range(arm.shape[1]):
            ax, ay = arm[n, p, 0], arm[n, p, 1]
            total = 0.0
            for j in range(S):
                if not assigned[n, j]:
                    continue
                a00 = sens_origin[n, j, 0, 0] + ax * s_theta[n, j, 0]
                a01 = sens_origin[n, j, 0, 1] + ax * s_theta[n, j, 1]
                a02 = sens_origin[n, j, 0, 2] + ax * s_theta[n, j, 2]
                a10 = sens_origin[n, j, 1, 0] + ay * s_theta[n, j, 0]
                a11 = sens_origin[n, j, 1, 1] + ay * s_theta[n, j, 1]
                a12 = sens_origin[n, j, 1, 2] + ay * s_theta[n, j, 2]
                fro2 = a00 * a00 + a01 * a01 + a10 * a10 + a11 * a11
                det = a00 * a11 - a01 * a10
                root = math.sqrt(max(fro2 * fro2 - 4 * det * det, 0.0))
                total += eps_d * math.sqrt(0.5 * (fro2 + root)) + phi * math.hypot(a02, a12)
            out[n, p] = total


class PoseFilter:
    """Incremental pose fit: one Kalman update per contact (filterpy).

    The lifted measurement model is linear, so the extended Kalman filter's
    linearization is exact and its estimate equals :func:`fit_batch` over the
    same contacts. The filter starts from the batch fit of the first contacts
    that determine the pose (two with non-parallel faces), with the information
    of those contacts as its covariance.

    >>> import math
    >>> f = PoseFilter(sigma_d=1.0, sigma_phi=0.05)
    >>> f.update((1, 0), (1, 0), (1, 0), 1.0)    # on face x = 1 of a unit square
    >>> f.update((0, 1), (0, 1), (0, 1), 1.0)    # on face y = 1
    >>> [round(v, 9) + 0.0 for v in f.pose]
    [0.0, 0.0, 0.0]
    """

    def __init__(self, sigma_d: float, sigma_phi: float) -> None:
        self._weights = np.array([1 / sigma_d**2, 1 / sigma_phi**2, 1 / sigma_phi**2])
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []
        self._ekf: ExtendedKalmanFilter | None = None

    def update(
        self,
        point: tuple[float, float],
        normal: tuple[float, float],
        face_normal: tuple[float, float],
        face_offset: float,
    ) -> None:
        """Fold in one contact (world point, measured unit normal) on a model face."""
        H, y = lifted_rows(
            np.asarray(point, float),
            np.asarray(normal, float),
            np.asarray(face_normal, float),
            np.asarray(face_offset, float),
        )
        if self._ekf is None:
            self._pending.append((H, y))
            Hs = np.concatenate([h for h, _ in self._pending])
            ys = np.concatenate([v for _, v in self._pending])
            Ws = np.tile(self._weights, len(self._pending))
            info = Hs.T @ (Ws[:, None] * Hs)
            if np.linalg.matrix_rank(info, tol=SHARE_SLACK * np.abs(info).max()) < 4:
                return
            ekf = ExtendedKalmanFilter(dim_x=4, dim_z=3)
            ekf.P = np.linalg.inv(info)
            ekf.x = ekf.P @ (Hs.T @ (Ws * ys))
            self._ekf = ekf
            return
        self._ekf.update(
            y, HJacobian=lambda _x, H=H: H, Hx=lambda x, H=H: H @ x, R=np.diag(1 / self._weights)
        )

    @property
    def ready(self) -> bool:
        return self._ekf is not None

    @property
    def state(self) -> np.ndarray:
        """Lifted state (c, s, bx, by)."""
        if self._ekf is None:
            raise ValueError("the pose is not determined yet (needs two non-parallel faces)")
        return np.asarray(self._ekf.x, dtype=float).reshape(4)

    @property
    def pose(self) -> tuple[float, float, float]:
        """(x, y, theta) of the current estimate."""
        c, s, bx, by = self.state
        rho = float(np.hypot(c, s))
        theta = float(np.arctan2(s, c))
        R = rotation_matrices(np.asarray(theta))
        t = -(R @ np.array([bx, by])) / rho
        return float(t[0]), float(t[1]), theta
