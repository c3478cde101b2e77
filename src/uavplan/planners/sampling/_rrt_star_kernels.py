"""RRT*'s loop in Numba: whole iterations of PPSwarm Alg. 1 (lines 3-10) without a Python round
trip, the fast path of :class:`uavplan.planners.sampling.rrt_star.RRTStarTree` where the tree's
segment
checker has a compiled form (:attr:`uavplan.problems.validity.MotionValidator.segment_kernel`).

:func:`grow` runs iterations until one of its stop conditions and returns a status that tells
the caller what to do before calling again (refill the sample block, rebuild the grid with a
finer cell, grow the arrays) or why it stopped (the iteration limit, a goal connection, a
shorter goal path). It builds the same tree as :meth:`RRTStarTree.iterate` (the reference; the
tests compare the two node by node) with the same arithmetic, but checks segments **lazily**,
one kernel call each, only where the answer matters (OMPL's ``delayCC``): the segment from the
nearest node first (if it is blocked the iteration ends), then the candidate parents in order
of cost through them (the first free one is the parent the reference picks among all free
ones: least cost, then lowest index), then only the candidates that the new node would make
cheaper (the rewiring test), then the goal segment. The reference checks all of them in one
batch; both decide the same, so only ``edge_checks`` differs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from uavplan.planners.sampling.grid_index import _grid_insert, _grid_near, _grid_nearest
from uavplan.problems._validity_kernels import static_world_ok
from uavplan.world.tolerances import REWIRE_TOL

#: The segment check the loop calls (the fused static kernel's serial build).
_segment_ok = static_world_ok.serial

# ``ctr`` (int64) entries
N, ITER, CHECKS, REWIRES, FOUND, REJECTED, POS, REJ_RUN, N_GOAL, BEST = range(10)
N_CTR = 10
# ``fl`` (float64) entries: the best goal path's length, the cell to rebuild the grid with, the
# length of a known path outside the tree (informed sampling takes the lesser of the two)
BEST_TOTAL, TARGET, BOUND = range(3)
N_FL = 3
# ``cfg`` (float64) entries
STEP, GOAL_RADIUS, NEAR_RADIUS, GAMMA, DIM, MEASURE, SCAN_LIMIT, INFORMED, MIN_CELL = range(9)
N_CFG = 9
# statuses of :func:`grow`
DONE, NEED_SAMPLES, REBUILD, GROW, GOAL, IMPROVED = range(6)
#: Informed sampling: rejections in a row after which the next sample is kept.
MAX_REJECTIONS = 1000


@njit(cache=True)
def dist3(a0, a1, a2, b0, b1, b2):  # pragma: no cover - numba
    dx = a0 - b0
    dy = a1 - b1
    dz = a2 - b2
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def best_goal(pts, cost, goal_nodes, n_goal, g):  # pragma: no cover - numba
    """The goal node with the least cost-to-come plus distance to ``g`` (the first among ties)
    and that total; (-1, inf) without goal nodes."""
    best = -1
    bt = np.inf
    for t in range(n_goal):
        u = goal_nodes[t]
        tot = cost[u] + dist3(pts[u, 0], pts[u, 1], pts[u, 2], g[0], g[1], g[2])
        if tot < bt:
            bt = tot
            best = u
    return best, bt


@njit(cache=True)
def distinct_goal_nodes(pts, parent, cost, goal_nodes, n_goal, g, k, slack):  # pragma: no cover
    """Up to ``k`` goal nodes, shortest goal path first, each on a branch of its own and with
    a goal path at most ``1 + slack`` times the shortest: a node is taken when its tree path
    passes through none of the taken ones' middle nodes (the ancestor half way along their
    paths), so the paths split before half way (often a different way between the
    obstacles)."""
    tot = np.empty(n_goal)
    for t in range(n_goal):
        u = goal_nodes[t]
        tot[t] = cost[u] + dist3(pts[u, 0], pts[u, 1], pts[u, 2], g[0], g[1], g[2])
    order = np.argsort(tot, kind="mergesort")
    out = np.full(k, -1, dtype=np.int64)
    mids = np.full(k, -1, dtype=np.int64)
    m = 0
    for oi in range(n_goal):
        if tot[order[oi]] > (1.0 + slack) * tot[order[0]]:
            break
        u = goal_nodes[order[oi]]
        ok = True
        v = u
        while v >= 0 and ok:
            for c in range(m):
                if v == mids[c]:
                    ok = False
            v = parent[v]
        if not ok:
            continue
        depth = 0
        v = u
        while parent[v] >= 0:
            depth += 1
            v = parent[v]
        v = u
        for _ in range(depth // 2):
            v = parent[v]
        out[m] = u
        mids[m] = v
        m += 1
        if m == k:
            break
    return out[:m]


@njit(cache=True)
def reparent(pts, parent, cost, first_child, next_sib, stack, j, new, c):  # pragma: no cover
    """Make ``new`` the parent of ``j`` at cost-to-come ``c`` and recompute the costs of ``j``'s
    subtree, depth first (cost = parent's cost + segment length, exactly)."""
    p = parent[j]
    if first_child[p] == j:  # unlink j from its old parent's children
        first_child[p] = next_sib[j]
    else:
        s = first_child[p]
        while next_sib[s] != j:
            s = next_sib[s]
        next_sib[s] = next_sib[j]
    parent[j] = new
    next_sib[j] = first_child[new]
    first_child[new] = j
    cost[j] = c
    top = 0
    ch = first_child[j]
    while ch >= 0:
        stack[top] = ch
        top += 1
        ch = next_sib[ch]
    while top > 0:
        top -= 1
        u = stack[top]
        q = parent[u]
        cost[u] = cost[q] + dist3(pts[u, 0], pts[u, 1], pts[u, 2], pts[q, 0], pts[q, 1], pts[q, 2])
        ch = first_child[u]
        while ch >= 0:
            stack[top] = ch
            top += 1
            ch = next_sib[ch]


@njit(cache=True)
def link(parent, cost, first_child, next_sib, new, best, c):  # pragma: no cover - numba
    """Attach the new leaf ``new`` under ``best`` at cost-to-come ``c``."""
    parent[new] = best
    cost[new] = c
    first_child[new] = -1
    next_sib[new] = first_child[best]
    first_child[best] = new


@njit(cache=True)
def _check(edge, a, b, kargs):  # pragma: no cover - numba
    for d in range(3):
        edge[0, 0, d] = a[d]
        edge[0, 1, d] = b[d]
    return _segment_ok(edge, kargs)[0]


@njit(cache=True)
def grow(
    pts, nxt, head, glo, cell, dims, parent, cost, first_child, next_sib, stack, goal_nodes,
    samples, goal_draw, startp, goalp, ctr, fl, cfg, max_iter, stop_at_goal, stop_on_improve,
    kargs,
):  # pragma: no cover - numba  # fmt: skip
    """Run RRT* iterations on the tree in these arrays (see the module) until ``ctr[ITER]``
    reaches ``max_iter`` (DONE), a node joins the goal with ``stop_at_goal`` (GOAL), the
    shortest goal path gets shorter with ``stop_on_improve`` (IMPROVED), or the caller must act
    first: NEED_SAMPLES (the block ``samples``/``goal_draw`` is used up), REBUILD (rebuild the
    grid with cell ``fl[TARGET]``, as :meth:`GridIndex.balance` would; never while the cell is
    ``cfg[MIN_CELL]`` or less), GROW (the arrays are full)."""
    step, goal_radius = cfg[STEP], cfg[GOAL_RADIUS]
    d, measure, informed = cfg[DIM], cfg[MEASURE], cfg[INFORMED] > 0
    n_blk = samples.shape[0]
    edge = np.empty((1, 2, 3))
    q = np.empty(3)
    x_new = np.empty(3)
    out = np.empty(64, dtype=np.int64)
    while ctr[ITER] < max_iter:
        n = ctr[N]
        if n >= pts.shape[0] or n >= parent.shape[0]:
            return GROW
        card = n + 1.0
        r = min(cfg[NEAR_RADIUS], cfg[GAMMA] * (np.log(card) / card) ** (1.0 / d))
        target = max(r, (measure / max(n, 1)) ** (1.0 / d))
        if 0 < target < 0.5 * cell and cell > cfg[MIN_CELL]:
            fl[TARGET] = target
            return REBUILD
        # line 3, with informed rejection (resumable across sample blocks)
        while True:
            i = ctr[POS]
            if i >= n_blk:
                return NEED_SAMPLES
            ctr[POS] = i + 1
            src = goalp if goal_draw[i] else samples[i]
            for a in range(3):
                q[a] = src[a]
            if not informed or ctr[N_GOAL] == 0 or ctr[REJ_RUN] >= MAX_REJECTIONS:
                break
            s = dist3(q[0], q[1], q[2], startp[0], startp[1], startp[2])
            s += dist3(q[0], q[1], q[2], goalp[0], goalp[1], goalp[2])
            if s < min(fl[BEST_TOTAL], fl[BOUND]):
                break
            ctr[REJECTED] += 1
            ctr[REJ_RUN] += 1
        ctr[REJ_RUN] = 0
        ctr[ITER] += 1
        # lines 4-5
        limit = min(cfg[SCAN_LIMIT] * n, 1e18)
        i_near, d2 = _grid_nearest(pts, n, head, nxt, glo, cell, dims, q, limit)
        d_near = np.sqrt(d2)
        if d_near <= 0.0:
            continue
        if d_near <= step:
            for a in range(3):
                x_new[a] = q[a]
        else:
            f = step / d_near
            for a in range(3):
                x_new[a] = pts[i_near, a] + (q[a] - pts[i_near, a]) * f
        # line 6: the nearest node's segment first
        ctr[CHECKS] += 1
        if not _check(edge, pts[i_near], x_new, kargs):
            continue
        # line 7
        k = _grid_near(pts, head, nxt, glo, cell, dims, x_new, r, out)
        if k > out.shape[0]:
            out = np.empty(2 * k, dtype=np.int64)
            k = _grid_near(pts, head, nxt, glo, cell, dims, x_new, r, out)
        cand = np.sort(out[:k])
        pos = np.searchsorted(cand, i_near)
        if pos == k or cand[pos] != i_near:
            cand = np.concatenate((cand[:pos], np.array([i_near]), cand[pos:]))
        m = cand.shape[0]
        dg = dist3(x_new[0], x_new[1], x_new[2], goalp[0], goalp[1], goalp[2])
        # insert the node (its links follow)
        new = n
        for a in range(3):
            pts[new, a] = x_new[a]
        _grid_insert(pts, new, head, nxt, glo, cell, dims)
        ctr[N] = n + 1
        # line 8: candidates by cost through them, checked until one is free
        state = np.zeros(m, dtype=np.int8)  # 0 unknown, 1 free, 2 blocked
        state[pos] = 1
        cc = np.empty(m)
        for t in range(m):
            u = cand[t]
            cc[t] = cost[u] + dist3(pts[u, 0], pts[u, 1], pts[u, 2], x_new[0], x_new[1], x_new[2])
        while True:
            bt = -1
            bc = np.inf
            for t in range(m):
                if state[t] != 2 and cc[t] < bc:
                    bc = cc[t]
                    bt = t
            if state[bt] == 0:
                ctr[CHECKS] += 1
                state[bt] = 1 if _check(edge, pts[cand[bt]], x_new, kargs) else 2
            if state[bt] == 1:
                break
        best = cand[bt]
        link(parent, cost, first_child, next_sib, new, best, bc)
        # line 9: rewire the candidates the new node makes cheaper
        rewired = 0
        for t in range(m):
            j = cand[t]
            if j == best or state[t] == 2:
                continue
            c = bc + dist3(pts[j, 0], pts[j, 1], pts[j, 2], x_new[0], x_new[1], x_new[2])
            if c + REWIRE_TOL < cost[j]:
                if state[t] == 0:
                    ctr[CHECKS] += 1
                    state[t] = 1 if _check(edge, pts[j], x_new, kargs) else 2
                if state[t] == 1:
                    reparent(pts, parent, cost, first_child, next_sib, stack, j, new, c)
                    rewired += 1
        ctr[REWIRES] += rewired
        # line 10
        joined = False
        if dg <= goal_radius:
            ctr[CHECKS] += 1
            if _check(edge, x_new, goalp, kargs):
                goal_nodes[ctr[N_GOAL]] = new
                ctr[N_GOAL] += 1
                joined = True
                if ctr[FOUND] == 0:
                    ctr[FOUND] = ctr[ITER]
        if (joined or rewired > 0) and ctr[N_GOAL] > 0:
            b, total = best_goal(pts, cost, goal_nodes, ctr[N_GOAL], goalp)
            improved = total < fl[BEST_TOTAL]
            ctr[BEST] = b
            fl[BEST_TOTAL] = total
            if joined and stop_at_goal:
                return GOAL
            if improved and stop_on_improve:
                return IMPROVED
    return DONE
