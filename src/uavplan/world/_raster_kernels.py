"""How far a raster's ground rises above (or falls below) the bilinear surface through its
values at a local grid's nodes, per local cell: the kernel behind the floor's and ceiling's
grids of a reprojected raster (:mod:`uavplan.world.raster`).

A local cell ``C`` (normalised coordinates ``(xi, eta)`` in ``[0, 1]^2``) maps into the
raster's sample space ``(u, v)`` (sample ``(row r, col c)`` at ``(c, r)``). ``S`` is the source
surface (bilinear through the samples), ``I`` the bilinear interpolant of ``S``'s values at
``C``'s four corners. :func:`cell_rise` returns an ``e(C) >= sup_C (S - I)``; nodes raised by
the largest ``e`` of their adjacent cells then carry a bilinear surface that is never below
``S`` (``I + e`` on every cell, as the corners' weights are a convex combination).

The bound, per cell:

* The map ``(xi, eta) -> (u, v)`` is taken as the affine map ``A`` closest to the bilinear map
  ``B`` through the corners' images (``|A - B| <= |c| / 4`` per axis, ``c`` the images' twist);
  ``B`` is within ``map_err`` pixels of the exact map (measured by the caller); the difference
  costs at most ``G (|A - B|_1 + 2 map_err)`` of height, ``G`` the steepest sample difference
  of the source cells involved (the slack).
* Under ``A`` the source grid cuts ``C`` into convex pieces, one per source cell, on each of
  which ``q = S o A - I`` is one quadratic. Its maximum over a piece is on the boundary unless
  its Hessian is negative definite (then also at the stationary point, if inside); the
  boundary lies on the 8 lines of ``C``'s and the source cell's edges, each clipped to the
  piece, along which ``q`` is a quadratic in one variable, maximised in closed form. So the
  maximum over a piece is exact, and ``e(C)`` is the largest over the pieces plus the slack.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

EPS_CLIP = 1e-12


@njit(cache=True, inline="always")
def _q(Q, x, y):  # pragma: no cover - numba
    return Q[0] + Q[1] * x + Q[2] * y + Q[3] * x * x + Q[4] * x * y + Q[5] * y * y


@njit(cache=True, inline="always")
def _sample(H, r, c):  # pragma: no cover - numba
    rows, cols = H.shape
    return H[min(max(r, 0), rows - 1), min(max(c, 0), cols - 1)]


@njit(cache=True)
def _line_max(Q, L, own, x0, y0, dx, dy):  # pragma: no cover - numba
    """The maximum of the quadratic ``Q`` along the line ``(x0, y0) + t (dx, dy)`` clipped to
    the 8 half-planes ``L[k] . (1, x, y) >= 0`` (but half-plane ``own``, the line's own);
    -inf when the clipped line is empty."""
    tlo = -np.inf
    thi = np.inf
    for k in range(8):
        if k == own:
            continue
        l0 = L[k, 0] + L[k, 1] * x0 + L[k, 2] * y0
        l1 = L[k, 1] * dx + L[k, 2] * dy
        if abs(l1) <= 1e-300:
            if l0 < -EPS_CLIP:
                return -np.inf
            continue
        t = -l0 / l1
        if l1 > 0:
            tlo = max(tlo, t)
        else:
            thi = min(thi, t)
    if not (tlo <= thi + EPS_CLIP) or not math.isfinite(tlo) or not math.isfinite(thi):
        return -np.inf
    c0 = _q(Q, x0, y0)
    c1 = (Q[1] + 2.0 * Q[3] * x0 + Q[4] * y0) * dx + (Q[2] + Q[4] * x0 + 2.0 * Q[5] * y0) * dy
    c2 = Q[3] * dx * dx + Q[4] * dx * dy + Q[5] * dy * dy
    m = max(c0 + tlo * (c1 + c2 * tlo), c0 + thi * (c1 + c2 * thi))
    if c2 < 0.0:
        ts = -c1 / (2.0 * c2)
        if tlo < ts < thi:
            m = max(m, c0 + ts * (c1 + c2 * ts))
    return m


@njit(cache=True)
def cell_rise(H, U, V, S, map_err):  # pragma: no cover - numba
    """``e(C)`` per local cell (see the module docstring): ``H`` (rows, cols) the source's
    samples, ``U``/``V`` (ny, nx) the nodes' sample coordinates, ``S`` (ny, nx) the source
    surface at the nodes, ``map_err`` the bilinear map's error in pixels. Returns
    (ny - 1, nx - 1), each >= 0."""
    rows, cols = H.shape
    ny, nx = U.shape
    out = np.zeros((ny - 1, nx - 1))
    Q = np.empty(6)
    L = np.empty((8, 3))
    for j in range(ny - 1):
        for i in range(nx - 1):
            u00, u10, u01, u11 = U[j, i], U[j, i + 1], U[j + 1, i], U[j + 1, i + 1]
            v00, v10, v01, v11 = V[j, i], V[j, i + 1], V[j + 1, i], V[j + 1, i + 1]
            cu = u11 - u10 - u01 + u00
            cv = v11 - v10 - v01 + v00
            # A: the affine map closest to the bilinear one
            au0, au1, au2 = u00 - 0.25 * cu, u10 - u00 + 0.5 * cu, u01 - u00 + 0.5 * cu
            av0, av1, av2 = v00 - 0.25 * cv, v10 - v00 + 0.5 * cv, v01 - v00 + 0.5 * cv
            du_pad = 0.25 * abs(cu) + map_err + 1e-9
            dv_pad = 0.25 * abs(cv) + map_err + 1e-9
            umin = min(u00, u10, u01, u11, au0, au0 + au1, au0 + au2, au0 + au1 + au2) - du_pad
            umax = max(u00, u10, u01, u11, au0, au0 + au1, au0 + au2, au0 + au1 + au2) + du_pad
            vmin = min(v00, v10, v01, v11, av0, av0 + av1, av0 + av2, av0 + av1 + av2) - dv_pad
            vmax = max(v00, v10, v01, v11, av0, av0 + av1, av0 + av2, av0 + av1 + av2) + dv_pad
            c_lo = max(math.floor(umin), -1)
            c_hi = min(math.ceil(umax) - 1, cols - 1)
            r_lo = max(math.floor(vmin), -1)
            r_hi = min(math.ceil(vmax) - 1, rows - 1)
            S00, S10, S01, S11 = S[j, i], S[j, i + 1], S[j + 1, i], S[j + 1, i + 1]
            tauL = S00 - S10 - S01 + S11
            best = -np.inf
            grad = 0.0
            # the half-planes of C: xi >= 0, 1 - xi >= 0, eta >= 0, 1 - eta >= 0
            L[0, 0], L[0, 1], L[0, 2] = 0.0, 1.0, 0.0
            L[1, 0], L[1, 1], L[1, 2] = 1.0, -1.0, 0.0
            L[2, 0], L[2, 1], L[2, 2] = 0.0, 0.0, 1.0
            L[3, 0], L[3, 1], L[3, 2] = 1.0, 0.0, -1.0
            for rs in range(r_lo, r_hi + 1):
                for cs in range(c_lo, c_hi + 1):
                    s00 = _sample(H, rs, cs)
                    s10 = _sample(H, rs, cs + 1)
                    s01 = _sample(H, rs + 1, cs)
                    s11 = _sample(H, rs + 1, cs + 1)
                    grad = max(grad, abs(s10 - s00), abs(s11 - s01), abs(s01 - s00),
                               abs(s11 - s10))  # fmt: skip
                    gu = s10 - s00
                    gv = s01 - s00
                    tau = s00 - s10 - s01 + s11
                    a0, a1, a2 = au0 - cs, au1, au2
                    b0, b1, b2 = av0 - rs, av1, av2
                    Q[0] = s00 + gu * a0 + gv * b0 + tau * a0 * b0 - S00
                    Q[1] = gu * a1 + gv * b1 + tau * (a0 * b1 + a1 * b0) - (S10 - S00)
                    Q[2] = gu * a2 + gv * b2 + tau * (a0 * b2 + a2 * b0) - (S01 - S00)
                    Q[3] = tau * a1 * b1
                    Q[4] = tau * (a1 * b2 + a2 * b1) - tauL
                    Q[5] = tau * a2 * b2
                    # the source cell's half-planes: du >= 0, 1 - du >= 0, dv >= 0, 1 - dv >= 0
                    L[4, 0], L[4, 1], L[4, 2] = a0, a1, a2
                    L[5, 0], L[5, 1], L[5, 2] = 1.0 - a0, -a1, -a2
                    L[6, 0], L[6, 1], L[6, 2] = b0, b1, b2
                    L[7, 0], L[7, 1], L[7, 2] = 1.0 - b0, -b1, -b2
                    # C's edges
                    m = _line_max(Q, L, 0, 0.0, 0.0, 0.0, 1.0)
                    m = max(m, _line_max(Q, L, 1, 1.0, 0.0, 0.0, 1.0))
                    m = max(m, _line_max(Q, L, 2, 0.0, 0.0, 1.0, 0.0))
                    m = max(m, _line_max(Q, L, 3, 0.0, 1.0, 1.0, 0.0))
                    # the source cell's edges: du = 0, du = 1 (gradient (a1, a2)); dv likewise
                    na = a1 * a1 + a2 * a2
                    if na > 0.0:
                        for k, off in ((4, 0.0), (5, 1.0)):
                            s = (off - a0) / na
                            m = max(m, _line_max(Q, L, k, s * a1, s * a2, -a2, a1))
                    nb = b1 * b1 + b2 * b2
                    if nb > 0.0:
                        for k, off in ((6, 0.0), (7, 1.0)):
                            s = (off - b0) / nb
                            m = max(m, _line_max(Q, L, k, s * b1, s * b2, -b2, b1))
                    # an interior maximum: Hessian [[2 Q3, Q4], [Q4, 2 Q5]] negative definite
                    det = 4.0 * Q[3] * Q[5] - Q[4] * Q[4]
                    if Q[3] < 0.0 and det > 0.0:
                        x = (-Q[1] * 2.0 * Q[5] + Q[2] * Q[4]) / det
                        y = (-Q[2] * 2.0 * Q[3] + Q[1] * Q[4]) / det
                        inside = True
                        for k in range(8):
                            if L[k, 0] + L[k, 1] * x + L[k, 2] * y < -EPS_CLIP:
                                inside = False
                        if inside:
                            m = max(m, _q(Q, x, y))
                    best = max(best, m)
            slack = grad * (0.25 * abs(cu) + 0.25 * abs(cv) + 4.0 * map_err)
            out[j, i] = max(best, 0.0) + slack
    return out


@njit(cache=True)
def cell_voids(void, U, V, pad):  # pragma: no cover - numba
    """Per local cell, whether any sample of a source cell that the cell's image may overlap
    (the box of its corners' images grown by ``pad`` pixels) is a void: (ny - 1, nx - 1)."""
    rows, cols = void.shape
    ny, nx = U.shape
    out = np.zeros((ny - 1, nx - 1), dtype=np.bool_)
    for j in range(ny - 1):
        for i in range(nx - 1):
            umin = min(U[j, i], U[j, i + 1], U[j + 1, i], U[j + 1, i + 1]) - pad
            umax = max(U[j, i], U[j, i + 1], U[j + 1, i], U[j + 1, i + 1]) + pad
            vmin = min(V[j, i], V[j, i + 1], V[j + 1, i], V[j + 1, i + 1]) - pad
            vmax = max(V[j, i], V[j, i + 1], V[j + 1, i], V[j + 1, i + 1]) + pad
            c0 = min(max(math.floor(umin), 0), cols - 1)
            c1 = min(max(math.ceil(umax), 0), cols - 1)
            r0 = min(max(math.floor(vmin), 0), rows - 1)
            r1 = min(max(math.ceil(vmax), 0), rows - 1)
            w = False
            for r in range(r0, r1 + 1):
                for c in range(c0, c1 + 1):
                    if void[r, c]:
                        w = True
            out[j, i] = w
    return out
