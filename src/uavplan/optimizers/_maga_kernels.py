"""Numba kernels of the batched P-MAGA (:class:`uavplan.optimizers.maga.MAGABatch`).

One call advances every lattice of a batch by one ask (or one tell) of Alg. 1, the operators of
:mod:`uavplan.optimizers.maga` applied agent by agent in the same order, so that a batch gives
the numbers of the reference optimizer (:class:`~uavplan.optimizers.maga.ReferenceMAGA`, one
object per lattice) for the same generators; ``tests/optimizers/test_maga_batch.py`` compares
them operator by operator and run by run.

Random numbers: NumPy's ``default_rng`` is PCG64 (XSL-RR 128/64, O'Neill 2014). Each lattice's
generator state (128-bit state and increment, and the 32-bit half a bounded integer draw keeps
for the next one) is copied into a row of a ``uint64`` array and advanced here exactly as NumPy
advances it: ``random`` is ``(next64 >> 11) * 2**-53``, ``integers`` Lemire's bounded draw on
buffered 32-bit halves, ``uniform(a, b)`` is ``a + (b - a) * random``. Every array draw of the
reference (``rng.random(n)``, ``rng.integers(k, size=n)``, ``rng.uniform(size=(n, d))``) is a
loop over its elements in C order here, and the draws come in the reference's order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# ---------------------------------------------------------------------- PCG64, as NumPy's
_MUL_HI = np.uint64(0x2360ED051FC65DA4)  # PCG's default 128-bit multiplier
_MUL_LO = np.uint64(0x4385DF649FCCF645)
_LOW32 = np.uint64(0xFFFFFFFF)
_U0 = np.uint64(0)
_U1 = np.uint64(1)
_U11 = np.uint64(11)
_U32 = np.uint64(32)
_U58 = np.uint64(58)
_U63 = np.uint64(63)
_U64 = np.uint64(64)
_TO_DOUBLE = 1.0 / 9007199254740992.0  # 2**-53

#: columns of a generator's row: state (high, low), increment (high, low), has_uint32, uinteger
STATE_COLUMNS = 6


def pcg64_row(bit_generator: np.random.PCG64) -> np.ndarray:
    """The row of a PCG64's state (see the module docstring)."""
    s = bit_generator.state
    state, inc = int(s["state"]["state"]), int(s["state"]["inc"])
    m = (1 << 64) - 1
    return np.array(
        [state >> 64, state & m, inc >> 64, inc & m, int(s["has_uint32"]), int(s["uinteger"])],
        dtype=np.uint64,
    )


def set_pcg64_row(bit_generator: np.random.PCG64, row: np.ndarray) -> None:
    """Put a row's state back into a PCG64 (it continues where the kernels stopped)."""
    r = [int(v) for v in row]
    bit_generator.state = {
        "bit_generator": "PCG64",
        "state": {"state": (r[0] << 64) | r[1], "inc": (r[2] << 64) | r[3]},
        "has_uint32": r[4],
        "uinteger": r[5],
    }


@njit(cache=True, inline="always")
def _mulhi(a: np.uint64, b: np.uint64) -> np.uint64:  # pragma: no cover - numba
    """The high 64 bits of the 128-bit product of two uint64."""
    a0, a1 = a & _LOW32, a >> _U32
    b0, b1 = b & _LOW32, b >> _U32
    p00, p01, p10, p11 = a0 * b0, a0 * b1, a1 * b0, a1 * b1
    mid = (p00 >> _U32) + (p01 & _LOW32) + (p10 & _LOW32)
    return p11 + (p01 >> _U32) + (p10 >> _U32) + (mid >> _U32)


@njit(cache=True)
def next64(st: np.ndarray) -> np.uint64:  # pragma: no cover - numba
    """PCG64's next 64-bit output: step the 128-bit LCG, then XSL-RR of the new state."""
    hi, lo = st[0], st[1]
    new_lo = lo * _MUL_LO
    new_hi = _mulhi(lo, _MUL_LO) + hi * _MUL_LO + lo * _MUL_HI
    lo2 = new_lo + st[3]
    carry = _U1 if lo2 < new_lo else _U0
    hi2 = new_hi + st[2] + carry
    st[0], st[1] = hi2, lo2
    x = hi2 ^ lo2
    rot = hi2 >> _U58
    return (x >> rot) | (x << ((_U64 - rot) & _U63))


@njit(cache=True)
def next32(st: np.ndarray) -> np.uint64:  # pragma: no cover - numba
    """NumPy's buffered 32-bit draw: the high half of a 64-bit output is kept for the next."""
    if st[4] != _U0:
        st[4] = _U0
        return st[5]
    n = next64(st)
    st[4] = _U1
    st[5] = n >> _U32
    return n & _LOW32


@njit(cache=True)
def random(st: np.ndarray) -> float:  # pragma: no cover - numba
    """``Generator.random()``: a double in [0, 1)."""
    return float(next64(st) >> _U11) * _TO_DOUBLE


@njit(cache=True)
def integers(st: np.ndarray, low: int, high: int) -> int:  # pragma: no cover - numba
    """``Generator.integers(low, high)`` (``high`` exclusive, ``high - low <= 2**32``):
    nothing drawn when the range holds one value, else Lemire's bounded draw."""
    rng = high - 1 - low
    if rng == 0:
        return low
    r = np.uint64(rng)
    excl = r + _U1
    m = next32(st) * excl
    left = m & _LOW32
    if left < excl:
        threshold = (_LOW32 - r) % excl
        while left < threshold:
            m = next32(st) * excl
            left = m & _LOW32
    return low + int(m >> _U32)


@njit(cache=True)
def draw_sequence(
    st: np.ndarray, kinds: np.ndarray, args: np.ndarray
) -> np.ndarray:  # pragma: no cover - numba
    """Test hook: draw ``kinds[k]`` (0 ``random()``, 1 ``integers(args[k, 0], args[k, 1])``, 2
    ``uniform(-1, 1)``) in turn; the values as float64."""
    out = np.empty(len(kinds))
    for k in range(len(kinds)):
        if kinds[k] == 0:
            out[k] = random(st)
        elif kinds[k] == 1:
            out[k] = integers(st, args[k, 0], args[k, 1])
        else:
            out[k] = -1.0 + 2.0 * random(st)
    return out


# ---------------------------------------------------------------------- operators (Fig. 3)
@njit(cache=True)
def _row(dst: np.ndarray, src: np.ndarray) -> None:  # pragma: no cover - numba
    """``dst[:] = src`` for 1-D arrays, as a plain loop (a slice assignment inlines Numba's
    broadcasting code at every use: seconds of compilation)."""
    for j in range(src.shape[0]):
        dst[j] = src[j]


@njit(cache=True)
def _draw_rows(
    st: np.ndarray, n: int, p: float, low: int, D: int, block: int,
    flags: np.ndarray, picks: np.ndarray,
) -> int:  # fmt: skip  # pragma: no cover - numba
    """An operator's draws, as the reference makes them: ``rng.random(n) < p`` into ``flags``,
    then ``rng.integers(low, n_w, size=n)`` into ``picks`` (zeros, nothing drawn, when
    ``n_w <= low``) for ``n_w`` waypoints of ``block`` genes; returns ``max(block, 1)``."""
    bl = max(block, 1)
    n_w = (D - 1) // bl + 1 if D else 0
    for r in range(n):
        flags[r] = random(st) < p
    for r in range(n):
        picks[r] = integers(st, low, n_w) if n_w > low else 0
    return bl


@njit(cache=True)
def crossover(
    st: np.ndarray, P1: np.ndarray, P2: np.ndarray, n: int, P_c: float, block: int,
    out: np.ndarray, flags: np.ndarray, picks: np.ndarray,
) -> None:  # fmt: skip  # pragma: no cover - numba
    """:func:`~uavplan.optimizers.maga.single_point_crossover` on rows ``0..n-1`` into ``out``."""
    D = P1.shape[1]
    bl = _draw_rows(st, n, P_c, 1, D, block, flags, picks)  # the cut: 1..n_w - 1
    for r in range(n):
        c = picks[r] if flags[r] else 0  # c = 0: every gene from P2
        for j in range(D):
            out[r, j] = P1[r, j] if j // bl < c else P2[r, j]


@njit(cache=True)
def mutate(
    st: np.ndarray, X: np.ndarray, r0: int, n: int, P_m: float, h: np.ndarray, block: int,
    lower: np.ndarray, upper: np.ndarray, flags: np.ndarray, picks: np.ndarray,
) -> None:  # fmt: skip  # pragma: no cover - numba
    """:func:`~uavplan.optimizers.maga.mutate_adjacent` on rows ``r0..r0+n-1`` of ``X``, in place
    (``np.clip``'s comparisons: ``x > lower ? x : lower``, then ``x < upper ? x : upper``)."""
    D = X.shape[1]
    bl = _draw_rows(st, n, P_m, 0, D, block, flags, picks)  # the waypoint: 0..n_w - 1
    for r in range(n):
        x = X[r0 + r]
        for j in range(D):
            step = (-1.0 + 2.0 * random(st)) * h[j]
            v = x[j] + step if flags[r] and j // bl == picks[r] else x[j]
            v = v if v > lower[j] else lower[j]
            x[j] = v if v < upper[j] else upper[j]


@njit(cache=True)
def turns_back(Q: np.ndarray) -> bool:  # pragma: no cover - numba
    """``any(turn_cosines(Q[None]) <= 0)`` for one polyline ``(n_p, d)``."""
    n_p, d = Q.shape
    for k in range(1, n_p - 1):
        dot = 0.0
        s_in = 0.0
        s_out = 0.0
        for j in range(d):
            a = Q[k, j] - Q[k - 1, j]
            b = Q[k + 1, j] - Q[k, j]
            dot += b * a
            s_in += a * a
            s_out += b * b
        norm = np.sqrt(s_out) * np.sqrt(s_in)
        if norm > 0 and dot / norm <= 0:
            return True
    return False


@njit(cache=True)
def smooth_row(Q: np.ndarray, passes: int) -> None:  # pragma: no cover - numba
    """In place: :func:`~uavplan.optimizers.maga.smooth_reference`'s passes on one polyline
    ``(n_p, d)``."""
    n_p, d = Q.shape
    if not turns_back(Q):
        return
    for _ in range(passes):
        for start in (1, 2):
            for k in range(start, n_p - 1, 2):
                dot = 0.0
                defined_in = False
                defined_out = False
                for j in range(d):
                    a = Q[k, j] - Q[k - 1, j]
                    b = Q[k + 1, j] - Q[k, j]
                    dot += a * b
                    defined_in |= a != 0
                    defined_out |= b != 0
                if dot <= 0 and defined_in and defined_out:
                    for j in range(d):
                        Q[k, j] = 0.5 * (Q[k - 1, j] + Q[k + 1, j])
        if not turns_back(Q):
            break


@njit(cache=True)
def smooth_rows(P: np.ndarray, passes: int) -> None:  # pragma: no cover - numba
    """In place: :func:`smooth_row` on every polyline of ``P`` ``(n, n_p, d)``."""
    for r in range(P.shape[0]):
        smooth_row(P[r], passes)


@njit(cache=True)
def smooth_and_clip(
    X: np.ndarray, n: int, block: int, passes: int, smooth: bool,
    lower: np.ndarray, upper: np.ndarray,
) -> None:  # fmt: skip  # pragma: no cover - numba
    """``clip(smooth(X))`` of :meth:`~uavplan.optimizers.maga.MAGA.new_agents` on rows
    ``0..n-1`` (``np.minimum(np.maximum(x, lower), upper)``'s comparisons)."""
    D = X.shape[1]
    if smooth and block >= 2 and D % block == 0 and D // block >= 3 and passes >= 1:
        for r in range(n):
            smooth_row(X[r].reshape((D // block, block)), passes)
    for r in range(n):
        for j in range(D):
            v = X[r, j]
            v = v if v >= lower[j] else lower[j]
            X[r, j] = v if v <= upper[j] else upper[j]


@njit(cache=True)
def argmin_first(F: np.ndarray) -> int:  # pragma: no cover - numba
    """``np.argmin`` of a 1-D array without NaN: the first least value."""
    b = 0
    for i in range(1, F.shape[0]):
        if F[i] < F[b]:
            b = i
    return b


@njit(cache=True)
def argmax_first(F: np.ndarray) -> int:  # pragma: no cover - numba
    """``np.argmax`` of a 1-D array without NaN: the first greatest value."""
    b = 0
    for i in range(1, F.shape[0]):
        if F[i] > F[b]:
            b = i
    return b


@njit(cache=True)
def compete(
    F: np.ndarray, nb: np.ndarray, Min: np.ndarray, winner: np.ndarray
) -> None:  # pragma: no cover - numba
    """:func:`~uavplan.optimizers.maga.competition` (Eq. 11) on one lattice."""
    for i in range(F.shape[0]):
        k = 0
        for q in range(1, nb.shape[1]):
            if F[nb[i, q]] < F[nb[i, k]]:
                k = q
        Min[i] = nb[i, k]
        winner[i] = F[nb[i, k]] > F[i]


@njit(cache=True)
def known_cost(
    x: np.ndarray, p1: np.ndarray, f1: float, p2: np.ndarray, f2: float
) -> float:  # pragma: no cover - numba
    """:meth:`~uavplan.optimizers.maga.MAGA._known_costs` of one row: its parent's cost if it
    equals ``p2`` (checked last) or ``p1``, else NaN."""
    if _equal(x, p2):
        return f2
    return f1 if _equal(x, p1) else np.nan


@njit(cache=True)
def _equal(a: np.ndarray, b: np.ndarray) -> bool:  # pragma: no cover - numba
    for j in range(a.shape[0]):  # noqa: SIM110 (numba: no generator in all())
        if a[j] != b[j]:
            return False
    return True


# ---------------------------------------------------------------------- one ask / tell of Alg. 1
# Per-lattice state (S lattices of N agents, D genes, K = sL_size ** 2 points per L_new):
#   ints[s] = (phase, iterations, generation, s_generation, n_targets, n_candidates, n_new)
#   phase 0: the main lattice's turn, 1: the self-learning lattices'
PHASE, ITER, GEN, SGEN, NTAR, NCAND, NNEW = 0, 1, 2, 3, 4, 5, 6
INT_COLUMNS = 7


@njit(cache=True)
def _new_agents(  # pragma: no cover - numba
    st, n, P_c, P_m, h, block, lower, upper, smooth, passes, pa, pb, out, flags, picks
):
    crossover(st, pa, pb, n, P_c, block, out, flags, picks)
    mutate(st, out, 0, n, P_m, h, block, lower, upper, flags, picks)
    if smooth:
        smooth_and_clip(out, n, block, passes, True, lower, upper)


@njit(cache=True)
def ask_all(
    live, states, ints, L, F, lower, upper, h, init, nb, snb, targets, sL, sF, elite_x,
    elite_f, cand, known, loser, asked, P_c, P_m, rate, best_only, block, smooth, passes,
):  # fmt: skip  # pragma: no cover - numba
    """One ask of every live lattice: its candidates (``cand[s, :ints[s, NCAND]]``) and their
    known costs (NaN unknown), which of them are asked, and the asked rows of all lattices,
    lattice by lattice, with the lattice of each row."""
    S, N, D = L.shape
    K = snb.shape[0]
    m = K - 1
    C = cand.shape[1]
    pa = np.empty((C, D))
    pb = np.empty((C, D))
    flags = np.empty(C, dtype=np.bool_)
    picks = np.empty(C, dtype=np.int64)
    Min = np.empty(N, dtype=np.int64)
    winner = np.empty(N, dtype=np.bool_)
    sMin = np.empty(K, dtype=np.int64)
    swin = np.empty(K, dtype=np.bool_)
    total = 0
    for s in range(S):
        if not live[s]:
            continue
        st = states[s]
        n = 0
        if ints[s, ITER] == 0:  # Alg. 1 lines 1-2: the first lattice
            if init.shape[0] > 0:
                for i in range(N):
                    _row(cand[s, i], init[s, i])
            else:
                for i in range(N):
                    for j in range(D):
                        cand[s, i, j] = lower[s, j] + random(st) * (upper[s, j] - lower[s, j])
            for i in range(N):
                known[s, i] = np.nan
            n = N
            ints[s, NNEW] = N
        elif ints[s, PHASE] == 0:  # the main lattice (MAGA._ask_lattice)
            b = argmin_first(F[s])
            _row(elite_x[s], L[s, b])
            elite_f[s] = F[s, b]
            compete(F[s], nb, Min, winner)
            nl = 0
            for i in range(N):
                if not winner[i]:
                    loser[s, nl] = i
                    _row(pa[nl], L[s, i])
                    _row(pb[nl], L[s, Min[i]])
                    nl += 1
            _new_agents(st, nl, P_c, P_m, h[s], block, lower[s], upper[s], smooth, passes,
                        pa, pb, cand[s], flags, picks)  # fmt: skip
            for r in range(nl):
                i = loser[s, r]
                known[s, r] = known_cost(cand[s, r], pa[r], F[s, i], pb[r], F[s, Min[i]])
            T = 0
            u = np.empty(N)
            for i in range(N):
                u[i] = random(st)
            if best_only:
                if u[b] < rate:
                    targets[s, 0] = b
                    T = 1
            else:
                for i in range(N):
                    if winner[i] and u[i] < rate:
                        targets[s, T] = i
                        T += 1
            ints[s, NTAR] = T
            for t in range(T):  # the mutants, after the new agents
                for k in range(m):
                    _row(cand[s, nl + t * m + k], L[s, targets[s, t]])
            mutate(st, cand[s], nl, T * m, 1.0, h[s], block, lower[s], upper[s], flags, picks)
            for r in range(T * m):
                p = targets[s, r // m]
                known[s, nl + r] = known_cost(cand[s, nl + r], L[s, p], F[s, p], L[s, p], F[s, p])
            n = nl + T * m
            ints[s, NNEW] = nl
        else:  # the self-learning lattices (MAGA._ask_self_learning)
            T = ints[s, NTAR]
            nl = 0
            for t in range(T):
                compete(sF[s, t], snb, sMin, swin)
                for p in range(K):
                    if not swin[p]:
                        loser[s, nl] = t * K + p
                        _row(pa[nl], sL[s, t, p])
                        _row(pb[nl], sL[s, t, sMin[p]])
                        known[s, nl] = sF[s, t, sMin[p]]  # parent 2's cost, for known_cost
                        nl += 1
            _new_agents(st, nl, P_c, P_m, h[s], block, lower[s], upper[s], smooth, passes,
                        pa, pb, cand[s], flags, picks)  # fmt: skip
            for r in range(nl):
                t, p = loser[s, r] // K, loser[s, r] % K
                known[s, r] = known_cost(cand[s, r], pa[r], sF[s, t, p], pb[r], known[s, r])
            n = nl
            ints[s, NNEW] = nl
        ints[s, NCAND] = n
        any_unknown = False
        for r in range(n):
            asked[s, r] = np.isnan(known[s, r])
            any_unknown |= asked[s, r]
        if not any_unknown:  # an ask is never empty
            for r in range(n):
                asked[s, r] = True
        for r in range(n):
            total += asked[s, r]
    X = np.empty((total, D))
    owner = np.empty(total, dtype=np.int64)
    k = 0
    for s in range(S):
        if not live[s]:
            continue
        for r in range(ints[s, NCAND]):
            if asked[s, r]:
                _row(X[k], cand[s, r])
                owner[k] = s
                k += 1
    return X, owner


@njit(cache=True)
def _end_generation(s, ints, L, F, elite_x, elite_f, elitism):  # pragma: no cover - numba
    if elitism:
        lowest = F[s, argmin_first(F[s])]
        if lowest > elite_f[s]:
            w = argmax_first(F[s])
            _row(L[s, w], elite_x[s])
            F[s, w] = elite_f[s]
    ints[s, GEN] += 1
    ints[s, PHASE] = 0


@njit(cache=True)
def _end_self_learning(
    s, ints, L, F, targets, s_best_x, s_best_f, elite_x, elite_f, elitism
):  # pragma: no cover - numba
    for t in range(ints[s, NTAR]):
        _row(L[s, targets[s, t]], s_best_x[s, t])
        F[s, targets[s, t]] = s_best_f[s, t]
    _end_generation(s, ints, L, F, elite_x, elite_f, elitism)


@njit(cache=True)
def tell_all(
    live, f, X, ints, L, F, targets, sL, sF, s_best_x, s_best_f, elite_x, elite_f, cand, known,
    loser, asked, best_x, best_f, has_best, evaluations, sGen, elitism,
):  # fmt: skip  # pragma: no cover - numba
    """The costs ``f`` of the rows of the last :func:`ask_all` (in its order) told to every live
    lattice: :meth:`Optimizer.tell`'s bookkeeping, then MAGA's ``_tell``. ``X``: the rows as
    evaluated, which replace the asked candidates (or no rows: as asked)."""
    S, N = F.shape
    K = sL.shape[2]
    m = K - 1
    k = 0
    for s in range(S):
        if not live[s]:
            continue
        n = ints[s, NCAND]
        # Optimizer.tell: the best of this batch (first least), then the evaluation count
        first = -1
        for r in range(n):
            if asked[s, r]:
                if X.shape[0] > 0:
                    _row(cand[s, r], X[k])
                known[s, r] = f[k]
                if first < 0 or f[k] < known[s, first]:
                    first = r
                k += 1
                evaluations[s] += 1
        if known[s, first] < best_f[s] or not has_best[s]:
            best_f[s] = known[s, first]
            _row(best_x[s], cand[s, first])
            has_best[s] = True
        nl = ints[s, NNEW]
        if ints[s, ITER] == 0:
            for i in range(N):
                _row(L[s, i], cand[s, i])
                F[s, i] = known[s, i]
        elif ints[s, PHASE] == 0:  # MAGA._tell_lattice
            for r in range(nl):
                _row(L[s, loser[s, r]], cand[s, r])  # New_ij occupies the loser's place
                F[s, loser[s, r]] = known[s, r]
            T = ints[s, NTAR]
            if T == 0:
                _end_generation(s, ints, L, F, elite_x, elite_f, elitism)
            else:
                for t in range(T):
                    _row(sL[s, t, 0], L[s, targets[s, t]])
                    sF[s, t, 0] = F[s, targets[s, t]]
                    for q in range(m):
                        _row(sL[s, t, 1 + q], cand[s, nl + t * m + q])
                        sF[s, t, 1 + q] = known[s, nl + t * m + q]
                    b = argmin_first(sF[s, t])
                    _row(s_best_x[s, t], sL[s, t, b])
                    s_best_f[s, t] = sF[s, t, b]
                ints[s, SGEN] = 0
                ints[s, PHASE] = 1
                if sGen == 0:
                    _end_self_learning(s, ints, L, F, targets, s_best_x, s_best_f,
                                       elite_x, elite_f, elitism)  # fmt: skip
        else:  # MAGA._tell_self_learning
            for r in range(nl):
                t, p = loser[s, r] // K, loser[s, r] % K
                _row(sL[s, t, p], cand[s, r])
                sF[s, t, p] = known[s, r]
            for t in range(ints[s, NTAR]):  # elite retention in L_new
                b = argmin_first(sF[s, t])
                best_now = sF[s, t, b]
                if best_now > s_best_f[s, t]:
                    w = argmax_first(sF[s, t])
                    _row(sL[s, t, w], s_best_x[s, t])
                    sF[s, t, w] = s_best_f[s, t]
                elif best_now < s_best_f[s, t]:
                    _row(s_best_x[s, t], sL[s, t, b])
                    s_best_f[s, t] = best_now
            ints[s, SGEN] += 1
            if ints[s, SGEN] >= sGen:
                _end_self_learning(s, ints, L, F, targets, s_best_x, s_best_f,
                                   elite_x, elite_f, elitism)  # fmt: skip
        ints[s, ITER] += 1
