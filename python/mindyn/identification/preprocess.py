"""The data path of inverse-dynamics identification: from a logged ``t, q, [dq], tau`` to the
samples the least squares are fitted on.

Steps, each recorded in ``JointData.processing["preprocess"]``:

1. **Time base.** The sample intervals are measured (median, extremes, jitter = largest
   deviation from the median relative to it, gaps over 1.5 median intervals). A log whose
   intervals vary is resampled onto a uniform grid at the median interval (positions by cubic
   spline, logged velocities and torques linearly), so that the filter and the derivatives work
   on a true time base.
2. **Period averaging** (when asked, ``periods`` or ``period``): a periodic excitation recorded
   over several periods is cut into whole periods (the grid is then chosen with a whole number
   of samples per period) and averaged sample by sample; the spread of the periods about their
   mean is reported. Periods that do not repeat (positions differing between periods by more
   than :data:`PERIODICITY_TOLERANCE` of the motion, or one period whose end does not run back
   into its start) and periods of fewer than :data:`MIN_PERIOD_SAMPLES` samples (refused
   before any array is made) are refused. The averaged period is filtered as a periodic signal
   (no edges).
3. **One zero-phase low-pass**: Butterworth of ``order`` in second-order sections run forwards
   and backwards (``scipy.signal.sosfiltfilt``). The cut-off is chosen from the data unless
   given: ``CUTOFF_FACTOR`` times the excited band, the frequency below which 99.9 % of the
   spectral energy of the positions lies (linear trend removed, Hann window), at most
   ``rate / 10``. Velocities are the filtered logged velocities, or the derivative of the
   filtered positions when none are logged; accelerations the derivative of the filtered
   velocities (central differences on the uniform grid). The measured torques go through the
   same filter, and so do the columns of the regressor (parallel filtering: the regressor is
   evaluated on the filtered motion at the full rate, then filtered, edge-dropped and
   decimated like the torques, see :class:`ParallelFilter`), so that ``tau_f = W_f p`` holds
   exactly for the model, the Coulomb sign columns included.
4. **Filter edges dropped**: ``edge`` seconds at each end (default :data:`EDGE_PERIODS`
   periods of the cut-off), where the zero-phase filter starts up.
5. **Decimation** to the useful band: every ``k``-th sample, ``k`` the largest whole number
   keeping the rate at least ``DECIMATION_MARGIN`` times the cut-off.

The sign of the Coulomb friction is then that of the filtered velocity; equations of joints
slower than ``min_velocity`` are left out by :func:`~mindyn.identification.identify`.

A break in the log (a sample interval longer than :data:`SEGMENT_GAP` median intervals) would
be bridged by the resampling and the filter, joining motion that did not happen: such a log is
refused by :func:`preprocess`; :func:`split_at_gaps` cuts it into segments that go through the
data path on their own and are then fitted together (as several logs are).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy import signal
from scipy.interpolate import CubicSpline

from .. import _args
from .._core import sosfilt_rows
from .._threads import evaluated_ahead
from .data import EDGE_PERIODS, DataError, check_cutoff
from .joint_data import JointData

__all__ = [
    "CUTOFF_FACTOR",
    "DECIMATION_MARGIN",
    "ParallelFilter",
    "concatenate",
    "excited_band",
    "preprocess",
    "require_even_stamps",
    "timing",
]

#: Cut-off of the low-pass as a multiple of the excited band of the positions.
CUTOFF_FACTOR = 10.0
#: Least ratio of the decimated sample rate to the cut-off.
DECIMATION_MARGIN = 10.0
#: Fraction of the position spectrum's energy that defines the excited band.
BAND_ENERGY = 0.999
#: Relative jitter of the sample intervals above which the log is resampled.
JITTER_TOLERANCE = 1e-3
#: Bytes of full-rate regressor columns filtered at once by :class:`ParallelFilter`.
PARALLEL_BUDGET = 256 * 2**20
#: Bytes of full-rate regressor blocks the block-wise parallel filter keeps from its forward pass
#: for its backward pass (each block not kept is evaluated again).
KEEP_BUDGET = 256 * 2**20
#: Samples whose regressor is evaluated at once.
_CHUNK = 8192

#: Fewest samples a period to be averaged may hold (the period averaging's grid).
MIN_PERIOD_SAMPLES = 8
#: Periodicity residual refused in period averaging: the RMS difference of the positions of
#: the periods from their mean, relative to the RMS motion of the joint about its mean. Sensor
#: noise and encoder steps give a small fraction of the motion; a wrong period count or period
#: gives a difference of the order of the motion itself.
PERIODICITY_TOLERANCE = 0.05

#: A sample interval longer than this many median intervals is a break in the log, not jitter
#: (the jittered logs we know reach 9 median intervals at most; a break of 20 intervals at the
#: decimated rate of 10 x the cut-off is two periods of the cut-off, over which the motion is
#: not known).
SEGMENT_GAP = 20.0


#: The filtered regressors a ParallelFilter keeps (the last base sets asked for).
KEPT_BASES = 4


class ParallelFilter:
    """The regressor columns filtered like the torques: ``regressor(base)`` evaluates
    ``base.regressor`` on the filtered full-rate motion, applies the same zero-phase low-pass,
    then the same edge drop and decimation, giving (m, n, nb) rows that match the preprocessed
    torques; the result is kept per base-parameter set.

    With the filter's second-order sections ``sos`` and its ``padlen`` (a log that is not an
    averaged period), the zero-phase filter runs block by block over time on all columns at
    once, with the arithmetic of ``scipy.signal.sosfiltfilt``: the regressor is evaluated once
    or twice per block (:data:`KEEP_BUDGET`), on two threads, never held whole. Otherwise
    ``lowpass`` filters whole columns, in blocks of at most :data:`PARALLEL_BUDGET` bytes.
    ``signals(fn)`` filters any columns ``fn(q, dq, ddq)`` of the full-rate motion alike."""

    def __init__(self, q, dq, ddq, lowpass, keep: slice, *, sos=None, padlen=None):
        self.q, self.dq, self.ddq = q, dq, ddq
        self.lowpass, self.keep = lowpass, keep
        self.sos, self.padlen = sos, padlen
        self._cache: dict = {}
        self._families: dict = {}

    def signals(self, fn) -> np.ndarray:
        """The columns ``fn(q, dq, ddq)`` ((k, w) for k samples of the filtered full-rate
        motion) low-passed like the torques, edge-dropped and decimated: shape (m, w)."""
        m = self.q.shape[0]
        idx = np.arange(m)[self.keep]
        if self.sos is not None:

            def rows(a, b):
                return fn(self.q[a:b], self.dq[a:b], self.ddq[a:b])

            return _filtfilt_blocks(self.sos, self.padlen, rows, m, idx)
        return self.lowpass(fn(self.q, self.dq, self.ddq))[idx]

    def regressor(self, base) -> np.ndarray:
        """The filtered base regressor (m, n, nb) of ``base``, kept for the last
        :data:`KEPT_BASES` base sets. A base set of a family (``base._family``: sets that
        differ in a few friction columns, as the friction models' searches try) starts from the
        first member's filtered regressor and filters its varied columns only."""
        key = id(base)
        hit = self._cache.get(key)
        if hit is not None and hit[0] is base:
            return hit[1]
        family: tuple | None = getattr(base, "_family", None)
        first = self._families.get(id(family[0])) if family is not None else None
        if family is not None and first is not None and first[0] is family[0]:
            out = self._varied(base, first[1])
        else:
            out = self._full(base)
            if family is not None:  # one family kept: the search running
                self._families = {id(family[0]): (family[0], out)}
        if len(self._cache) >= KEPT_BASES:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = (base, out)
        return out

    def _varied(self, base, first: np.ndarray) -> np.ndarray:
        """``first`` (a family member's filtered regressor) with the columns of ``base`` that
        vary in the family (``base._varied()``) filtered in."""
        cols = [c for c, _, _ in base._varied()]
        out = first.copy()
        if cols:
            n, w = self.q.shape[1], len(cols)

            def rows(q, dq, ddq):
                return base._varied_regressor(q, dq, ddq).reshape(q.shape[0], n * w)

            out[:, :, cols] = self.signals(rows).reshape(out.shape[0], n, w)
        return out

    def _full(self, base) -> np.ndarray:
        m, n = self.q.shape
        nb = base.n
        idx = np.arange(m)[self.keep]
        if self.sos is not None:

            def rows(q, dq, ddq):
                return base.regressor(q, dq, ddq).reshape(q.shape[0], n * nb)

            return self.signals(rows).reshape(idx.size, n, nb)
        out = np.empty((idx.size, n, nb))
        block = max(1, min(nb, PARALLEL_BUDGET // (8 * m * n)))
        for c0 in range(0, nb, block):
            c1 = min(nb, c0 + block)
            W = np.empty((m, n, c1 - c0))
            for a in range(0, m, _CHUNK):
                b = min(m, a + _CHUNK)
                W[a:b] = base.regressor(self.q[a:b], self.dq[a:b], self.ddq[a:b])[:, :, c0:c1]
            out[:, :, c0:c1] = self.lowpass(W)[idx]
        return out


def _filtfilt_blocks(sos, padlen: int, rows, m: int, idx: np.ndarray) -> np.ndarray:
    """``scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)[idx]`` of a signal ``x``
    (m, w) given by ``rows(a, b)`` -> ``x[a:b]``, without holding ``x`` whole: the forward pass
    runs block by block keeping the filter state at the start of each block, the backward pass
    runs from the last block to the first, recomputing each block's forward output from its
    state. The operations, and so the values, are those of ``sosfiltfilt`` (odd extension of
    ``padlen`` samples at each end, the steady-state initial conditions of ``sosfilt_zi``
    scaled by the first sample of each pass; each section's update as ``sosfilt`` makes it);
    ``x`` is produced twice, but for the last blocks, kept from the forward pass within
    :data:`KEEP_BUDGET` bytes. The sections run down the rows of each block, all columns side
    by side (``_core.sosfilt_rows``, without the interpreter lock), while the next blocks are
    produced on threads (:func:`~mindyn._threads.evaluated_ahead`). Columns that are zero in
    every sample (a regressor's structural zeros) are not filtered: their output is zero, as
    ``sosfiltfilt``'s."""

    def block(a, b):  # with adjacent columns, as the filter reads them
        return np.ascontiguousarray(rows(a, b))

    head, tail = block(0, padlen + 1), block(m - padlen - 1, m)
    cols = np.flatnonzero(np.any(head != 0, axis=0) | np.any(tail != 0, axis=0))
    passed = _forward_states(sos, padlen, block, m, head, tail, cols)
    if passed is None:  # a column zero at both ends moves in between: filter every column
        cols = np.arange(head.shape[1])
        passed = _forward_states(sos, padlen, block, m, head, tail, cols)
    bounds, states, z, kept = passed
    out = np.zeros((idx.size, head.shape[1]))
    back = bounds[::-1]
    # the kept blocks hold the columns cols already; the others are read at them
    again = ((x, cols) for x in evaluated_ahead(block, back[len(kept) :]))
    blocks = itertools.chain(((x, None) for x in reversed(kept)), again)
    for (a, b), state, (x, pick) in zip(back, reversed(states), blocks):
        y = np.empty((b - a, cols.size))
        sosfilt_rows(sos, x, state, pick, y)  # the block's forward output, from its state
        sosfilt_rows(sos, y[::-1], z, None, y[::-1])  # backward, in place
        lo, hi = np.searchsorted(idx, [a, b])
        out[lo:hi, cols] = y[idx[lo:hi] - a]
    return out


def _forward_states(sos, padlen, rows, m, head, tail, cols):
    """The forward pass of :func:`_filtfilt_blocks` over columns ``cols`` of the signal:
    ``(bounds, states, z, kept)``, the blocks, the filter state at the start of each
    (sections, 2, columns), the state of the backward pass after the right extension, and the
    columns ``cols`` of the last blocks (as many as :data:`KEEP_BUDGET` holds: the backward
    pass starts with them); None when a column not in ``cols`` is not zero somewhere."""
    zi = signal.sosfilt_zi(sos)[:, :, None]  # (sections, 2, 1): state per column
    head, tail = head[:, cols], tail[:, cols]
    left = np.ascontiguousarray(2 * head[:1] - head[padlen:0:-1])
    right = np.ascontiguousarray(2 * tail[-1:] - tail[-2 : -(padlen + 2) : -1])
    z = zi * left[0]
    sosfilt_rows(sos, left, z)
    bounds = [(a, min(m, a + _CHUNK)) for a in range(0, m, _CHUNK)]
    states = []
    keep = min(len(bounds), KEEP_BUDGET // (8 * _CHUNK * max(cols.size, 1)))
    kept = []
    others = None
    for k, x in enumerate(evaluated_ahead(rows, bounds)):
        states.append(z.copy())
        if others is None:  # the columns outside cols
            others = np.ones(x.shape[1], dtype=bool)
            others[cols] = False
        if others.any() and np.any(np.any(x != 0, axis=0)[others]):
            return None
        if k >= len(bounds) - keep:
            kept.append(np.take(x, cols, axis=1))  # C-ordered, as the filter reads it
        sosfilt_rows(sos, x, z, cols)
    y = np.empty_like(right)
    sosfilt_rows(sos, right, z, None, y)
    z = zi * y[-1]
    sosfilt_rows(sos, y[::-1], z)
    return bounds, states, z, kept


@_args.finite_results("t")
def timing(t: np.ndarray) -> dict:
    """Statistics of the sample intervals of ``t`` (m,): median, min, max [s], ``jitter`` (largest
    deviation from the median relative to it), ``rms_jitter`` and the number of ``gaps`` longer
    than 1.5 median intervals."""
    t = _args.array(t, "t", (None,))
    dt = np.diff(t)
    med = float(np.median(dt))
    dev = np.abs(dt - med) / med
    return {
        "median_dt_s": med,
        "min_dt_s": float(dt.min()),
        "max_dt_s": float(dt.max()),
        "rate_Hz": 1.0 / med,
        "jitter": float(dev.max()),
        "rms_jitter": float(np.sqrt(np.mean(dev**2))),
        "gaps": int(np.sum(dt > 1.5 * med)),
    }


def excited_band(q: np.ndarray, dt: float, *, energy: float = BAND_ENERGY) -> float:
    """Frequency [Hz] below which ``energy`` of the spectral energy of the positions ``q`` (m, n)
    on a uniform grid of step ``dt`` lies, all joints together; the straight line between the
    first and last sample is removed first (a motion that does not return to its start would
    otherwise show as a broad-band ramp) and a Hann window applied."""
    q = _args.array(q, "q", (None, None))
    dt = _args.number(dt, "dt", positive=True)
    energy = _args.number(energy, "energy", positive=True, maximum=1.0)
    m = q.shape[0]
    ramp = np.linspace(0.0, 1.0, m)[:, None] * (q[-1] - q[0])
    x = (q - q[0] - ramp) * np.hanning(m)[:, None]
    largest = np.abs(x).max() if x.size else 0.0
    if largest > 0:  # the band is the same for x / largest, whose power cannot overflow
        x = x / largest
    power = np.sum(np.abs(np.fft.rfft(x, axis=0)) ** 2, axis=1)
    freq = np.fft.rfftfreq(m, dt)
    total = power.sum()
    if not total > 0:
        return float("nan")
    k = int(np.searchsorted(np.cumsum(power) / total, energy))
    return float(freq[min(max(k, 1), freq.size - 1)])


def _resample(t, tu, q, dq, tau):
    """Positions by cubic spline, velocities and torques linearly, onto ``tu``."""
    qu = CubicSpline(t, q, axis=0)(tu)

    def lin(x):
        return None if x is None else np.column_stack([np.interp(tu, t, c) for c in x.T])

    return qu, lin(dq), lin(tau)


def _check_periodic(Q: np.ndarray, cycle: dict, src: str, duration: float) -> None:
    """Refuses periods (``Q`` of shape (periods, samples, n)) that do not repeat: several
    periods whose positions differ (beyond the sensor noise, estimated from second differences)
    by more than :data:`PERIODICITY_TOLERANCE` of the motion, or
    one period whose end does not run back into its start (a jump from the last sample to the
    first over 3 times the largest step between neighbouring samples). Records the residual in
    ``cycle["periodicity_residual"]``."""
    count, per, _ = Q.shape
    flat = Q.reshape(count * per, -1)
    motion = np.sqrt(np.mean((flat - flat.mean(axis=0)) ** 2, axis=0))
    # sensor noise from second differences (a smooth motion adds little to them): a joint held
    # still shows only noise, which differs between periods without saying anything of them
    noise = np.sqrt(np.mean(np.diff(flat, 2, axis=0) ** 2, axis=0) / 6.0)
    moving = motion > 10.0 * noise + 1e-12 * max(1.0, float(np.max(np.abs(flat))))
    if not moving.any():
        return
    if count > 1:
        spread = np.sqrt(np.mean((Q - Q.mean(axis=0)) ** 2, axis=(0, 1)))
        excess = np.sqrt(np.maximum(spread**2 - noise**2, 0.0))  # beyond the noise
        rel = np.where(moving, excess / np.where(moving, motion, 1.0), 0.0)
        what = "positions differ between periods by"
    else:
        step = np.max(np.abs(np.diff(Q[0], axis=0)), axis=0)
        jump = np.abs(Q[0, -1] - Q[0, 0])
        rel = np.where(moving, jump / np.maximum(3 * step, 1e-300), 0.0)
        what = "end jumps back to its start by"
    j = int(np.argmax(rel))
    cycle["periodicity_residual"] = float(rel[j])
    limit = PERIODICITY_TOLERANCE if count > 1 else 1.0
    if rel[j] > limit:
        detail = (
            f"{100 * rel[j]:.3g} % of its motion (at most {100 * limit:g} %)"
            if count > 1
            else f"{rel[j] * 3:.3g} times its largest step between samples (at most 3)"
        )
        raise DataError(
            f"{src}: the log ({duration:.6g} s) is not {count} period(s) of "
            f"{cycle['period_s']:.6g} s: joint {j + 1}'s {what} {detail}; give the number of "
            "periods the log holds (periods=) or the excitation's period (period=)"
        )


def require_even_stamps(data: JointData, filter: str) -> None:
    """Refuses ``data`` whose velocities or accelerations were derived by ``filter``
    (``butter`` or ``savgol``: filters designed for evenly spaced samples) when its time stamps
    are not: a jitter over :data:`JITTER_TOLERANCE` of the median interval or intervals over
    1.5 of it (gaps). The data path of :func:`preprocess` resamples such a log onto a uniform
    grid first; these filters do not. ``none`` (central differences on the time stamps, which
    ``numpy.gradient`` takes as they are) is not refused."""
    _args.instance(data, "data", JointData)
    _args.text(filter, "filter")
    if filter not in ("butter", "savgol"):
        return
    derived = [
        what
        for what in ("velocity", "acceleration")
        if data.processing.get(what, {}).get("source", "logged") != "logged"
    ]
    if not derived or data.m < 3:
        return
    tm = timing(data.t)
    if tm["jitter"] <= JITTER_TOLERANCE and tm["gaps"] == 0:
        return
    raise DataError(
        f"{data.source or 'data'}: filter='{filter}' derives the "
        + " and ".join("velocities" if w == "velocity" else "accelerations" for w in derived)
        + " as if the samples were evenly spaced, but its time stamps are not (intervals "
        f"{1e3 * tm['min_dt_s']:.4g} to {1e3 * tm['max_dt_s']:.4g} ms about a median of "
        f"{1e3 * tm['median_dt_s']:.4g} ms, jitter {100 * tm['jitter']:.3g} %, {tm['gaps']} "
        "gap(s)); use filter='lowpass' (the default), which resamples onto a uniform grid and "
        "cuts the log at its breaks"
    )


def split_at_gaps(data: JointData, *, gap: float = SEGMENT_GAP) -> list[JointData]:
    """``data`` cut at every sample interval longer than ``gap`` median intervals: a list of
    :class:`JointData` segments (one when there is no break), each with ``processing["segment"]``
    giving its index, count and time span, and its source naming the span."""
    dt = np.diff(data.t)
    if dt.size == 0:
        return [data]
    cuts = np.flatnonzero(dt > gap * np.median(dt)) + 1
    if cuts.size == 0:
        return [data]
    bounds = np.concatenate([[0], cuts, [data.m]])
    out = []
    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        span = (float(data.t[a]), float(data.t[b - 1]))
        out.append(
            JointData(
                data.t[a:b],
                data.q[a:b],
                None if data.dq is None else data.dq[a:b],
                None if data.ddq is None else data.ddq[a:b],
                None if data.tau is None else data.tau[a:b],
                f"{data.source or 'data'} [{span[0]:g} s to {span[1]:g} s]",
                {
                    **data.processing,
                    "segment": {"index": k, "of": len(bounds) - 1, "t_s": list(span)},
                },
                units_checked=data.units_checked,
            )
        )
    return out


def preprocess(
    data: JointData,
    *,
    cutoff: float | None = None,
    order: int = 4,
    periods: int | None = None,
    period: float | None = None,
    edge: float | None = None,
    decimate: bool = True,
    parallel: bool = True,
    gap: float = SEGMENT_GAP,
) -> JointData:
    """The data path of the module docstring applied to ``data`` (its ``q``, its ``dq`` when
    logged, its ``tau``); returns new :class:`JointData` with ``processing["preprocess"]``
    recording every choice.

    Parameters
    ----------
    cutoff : float, optional
        Low-pass cut-off [Hz]; default from the data (:func:`excited_band` x
        :data:`CUTOFF_FACTOR`, at most a tenth of the rate).
    order : int
        Butterworth order (the zero-phase filter has twice this order).
    periods, period : int or float, optional
        Average a periodic log: the log holds ``periods`` whole periods, or the period is
        ``period`` seconds (as many whole periods as the log holds are used). At most one.
    edge : float, optional
        Seconds dropped at each end after filtering (default ``EDGE_PERIODS / cutoff``; none
        for an averaged period).
    decimate : bool
        Keep every k-th sample (rate at least :data:`DECIMATION_MARGIN` x cutoff).
    gap : float
        A sample interval longer than ``gap`` median intervals is a break, refused
        (:func:`split_at_gaps`); ``numpy.inf`` bridges every break.
    parallel : bool
        Filter the regressor columns like the torques (:class:`ParallelFilter`, attached as
        ``regressor_filter``; used by the dynamic model, by the energy and integral models'
        friction columns and by predictions on this data).

    Raises
    ------
    DataError
        Bad settings (named), too short a log for the filter, the periods or the edges.
    """
    _args.instance(data, "data", JointData)
    cutoff = _args.optional(_args.number, cutoff, "cutoff", positive=True)
    order = _args.integer(order, "order", 1, maximum=10)
    periods = _args.optional(_args.integer, periods, "periods", 1)
    period = _args.optional(_args.number, period, "period", positive=True)
    edge = _args.optional(_args.number, edge, "edge", minimum=0.0)
    decimate = _args.flag(decimate, "decimate")
    parallel = _args.flag(parallel, "parallel")
    gap = gap if gap == np.inf else _args.number(gap, "gap", positive=True)
    src = data.source or "data"
    if not (isinstance(order, (int, np.integer)) and 1 <= order <= 10):
        raise DataError(f"filter order must be an integer from 1 to 10, got {order}")
    if periods is not None and period is not None:
        raise DataError("give the number of periods or the period, not both")
    if cutoff is not None and not (math.isfinite(cutoff) and cutoff > 0):
        raise DataError(f"cutoff must be a positive number of Hz, got {cutoff}")
    if edge is not None and not (math.isfinite(edge) and edge >= 0):
        raise DataError(f"edge must be a number of seconds >= 0, got {edge}")
    if data.m < 8:
        raise DataError(f"{src}: {data.m} samples are too few to filter")
    logged_dq = data.processing.get("velocity", {}).get("source", "logged") == "logged"
    info: dict = {"timing": timing(data.t)}
    t = data.t - data.t[0]
    dt = info["timing"]["median_dt_s"]
    longest = info["timing"]["max_dt_s"]
    if longest > gap * dt:
        k = int(np.argmax(np.diff(data.t)))
        raise DataError(
            f"{src}: a break of {longest:.4g} s ({longest / dt:.3g} median intervals) after "
            f"t = {data.t[k]:.6g} s; the resampling and the filter would bridge it: "
            "preprocess each segment on its own (split_at_gaps)"
        )

    # 1-2: time base, period averaging
    cycle = None
    if periods is not None or period is not None:
        duration = t[-1] + dt  # the last sample's interval belongs to the log
        if periods is not None:
            if not (isinstance(periods, (int, np.integer)) and periods >= 1):
                raise DataError(f"periods must be a whole number >= 1, got {periods}")
            T, count = duration / periods, int(periods)
        else:
            assert period is not None
            if not (math.isfinite(period) and period > 0):
                raise DataError(f"period must be a positive number of seconds, got {period}")
            T, count = float(period), int(math.floor(duration / period * (1 + 1e-9)))
            if count < 1:
                raise DataError(
                    f"{src}: the log lasts {duration:.6g} s, shorter than the period {T:g} s"
                )
        # before any array of count x per samples is made: a period of a few sample intervals
        # (a typo such as 1e-6 s) would ask for millions of them
        if not T / dt >= MIN_PERIOD_SAMPLES:
            given = (
                f"{periods} periods in its {duration:.6g} s make a period of {T:.3g} s,"
                if periods is not None
                else f"the period {T:.3g} s is"
            )
            raise DataError(
                f"{src}: {given} {T / dt:.3g} sample intervals ({dt:.6g} s); a period to "
                f"average needs at least {MIN_PERIOD_SAMPLES} (is the period in seconds, the "
                "count whole periods of the excitation?)"
            )
        per = int(round(T / dt))
        dt = T / per
        cycle = {"period_s": T, "periods": count, "samples_per_period": per}
        tu = np.arange(count * per) * dt
        tu = tu[tu <= t[-1]]
        if tu.size < count * per:  # the last period ends a fraction of a sample after the log
            tu = np.append(tu, np.full(count * per - tu.size, t[-1]))
    else:
        tu = t[0] + np.arange(int(math.floor(t[-1] / dt + 1e-9)) + 1) * dt
    uniform = info["timing"]["jitter"] <= JITTER_TOLERANCE and cycle is None
    if uniform:
        q, dq, tau = data.q, data.dq if logged_dq else None, data.tau
        tu = t
    else:
        q, dq, tau = _resample(t, tu, data.q, data.dq if logged_dq else None, data.tau)
    info["time_base"] = (
        "uniform as logged"
        if uniform
        else f"resampled to a uniform grid of {dt:.6g} s (positions by cubic spline, "
        + ("velocities and " if dq is not None else "")
        + "torques linearly)"
    )
    rate = 1.0 / dt

    if cycle is not None:

        def fold(x):
            return (
                None if x is None else x.reshape(cycle["periods"], cycle["samples_per_period"], -1)
            )

        Q, DQ, TAU = fold(q), fold(dq), fold(tau)
        if cycle["periods"] > 1 and TAU is not None:
            spread = np.sqrt(np.mean((TAU - TAU.mean(axis=0)) ** 2, axis=(0, 1)))
            cycle["torque_spread_rms"] = spread.tolist()
        if cycle["periods"] > 1:
            qs = np.sqrt(np.mean((Q - Q.mean(axis=0)) ** 2, axis=(0, 1)))
            cycle["position_spread_rms"] = qs.tolist()
        _check_periodic(Q, cycle, src, duration)
        q = Q.mean(axis=0)
        dq = None if DQ is None else DQ.mean(axis=0)
        tau = None if TAU is None else TAU.mean(axis=0)
        tu = tu[: cycle["samples_per_period"]]
        info["averaging"] = cycle

    # 3: one low-pass
    band = excited_band(q, dt)
    info["excited_band_Hz"] = band
    if cutoff is None:
        if not math.isfinite(band):
            raise DataError(f"{src}: the positions do not move; no cut-off can be chosen")
        fc = min(CUTOFF_FACTOR * band, rate / 10.0)
        info["cutoff_source"] = (
            f"{CUTOFF_FACTOR:g} x the excited band ({100 * BAND_ENERGY:g} % of the position "
            "spectrum's energy)" + (", limited to rate / 10" if fc < CUTOFF_FACTOR * band else "")
        )
    else:
        fc = float(cutoff)
        info["cutoff_source"] = "given"
        check_cutoff(fc, rate, float(t[-1] - t[0]), source=src)
    sos = signal.butter(order, fc, fs=rate, output="sos")
    periodic = cycle is not None
    m = q.shape[0]

    padlen = min(m - 1, max(3 * (2 * len(sos) + 1), int(3 * rate / fc)))

    def lowpass(x):
        if periodic:  # one period, filtered as the periodic signal it is
            reps = 1 + 2 * int(math.ceil(3 * rate / fc / m))
            y = signal.sosfiltfilt(sos, np.concatenate([x] * reps, axis=0), axis=0)
            k = reps // 2
            return y[k * m : (k + 1) * m]
        return signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)

    def derivative(x):
        if periodic:
            return (np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0)) / (2 * dt)
        return np.gradient(x, dt, axis=0)

    if m <= 3 * (2 * len(sos) + 1):
        raise DataError(f"{src}: {m} samples are too few for a Butterworth filter of order {order}")
    qf = lowpass(q)
    dqf = lowpass(dq) if dq is not None else derivative(qf)
    ddqf = derivative(dqf)
    tauf = lowpass(tau) if tau is not None else None
    info["filter"] = {
        "type": "butterworth, second-order sections, zero-phase (sosfiltfilt)"
        + (", periodic" if periodic else ""),
        "order": order,
        "cutoff_Hz": fc,
        "applied_to": "positions, "
        + ("logged velocities, " if dq is not None else "")
        + ("torques" if tau is not None else ""),
    }
    info["velocity"] = (
        "filtered logged velocities" if dq is not None else "derivative of the filtered positions"
    )
    info["acceleration"] = "derivative of the filtered velocities (central differences)"

    # 4: edges
    if edge is None:
        edge = 0.0 if periodic else EDGE_PERIODS / fc
    span = edge * rate
    drop = m if not span < m else (int(math.ceil(span - 1e-9)) if edge > 0 else 0)
    if m - 2 * drop < 8:
        raise DataError(
            f"{src}: dropping {edge:g} s at each end (filter edges) leaves {max(m - 2 * drop, 0)} "
            "samples; give a longer log, a smaller edge or a higher cutoff"
        )
    info["edge_s"] = drop * dt
    info["edge_samples_dropped"] = 2 * drop

    # 5: decimation
    k = max(1, int(math.floor(rate / (DECIMATION_MARGIN * fc) + 1e-9))) if decimate else 1
    keep = slice(drop, m - drop, k)
    info["decimation"] = k
    info["rate_Hz"] = rate / k
    info["parallel_filtering"] = bool(parallel and tauf is not None)
    out = JointData(
        tu[keep] + data.t[0],
        qf[keep],
        dqf[keep],
        ddqf[keep],
        None if tauf is None else tauf[keep],
        source=data.source,
        processing={**data.processing, "preprocess": info},
        units_checked=data.units_checked,
    )
    info["samples"] = out.m
    if info["parallel_filtering"]:
        blocks = {} if periodic else {"sos": sos, "padlen": padlen}
        out.regressor_filter = ParallelFilter(qf, dqf, ddqf, lowpass, keep, **blocks)
    out.processing["velocity"] = {"source": info["velocity"]}
    out.processing["acceleration"] = {"source": info["acceleration"]}
    with_dq = logged_dq and data.dq is not None
    out.logged = _logged_samples(data, tu, qf, dqf, ddqf, drop, cycle, fc, rate, with_dq)
    info["logged_samples"] = out.logged.m
    return out


def _logged_samples(data, tu, qf, dqf, ddqf, drop, cycle, fc, rate, logged_dq) -> JointData:
    """The samples of ``data`` as logged (time stamps, torques) whose stamps lie between the
    dropped filter edges (an averaged period: every sample of the whole periods, at its phase),
    with the filtered motion at those stamps: the filtered grid itself when the log was not
    resampled, else its cubic spline (periodic for an averaged period). Its
    ``processing["velocity_noise"]`` gives the white-noise level of the logged velocities (of
    the central differences of the logged positions when none are logged), per joint, from
    second differences (:func:`~mindyn.identification.models.torque_noise`), and
    ``filtered``: that level through the low-pass, ``sqrt(2 cutoff / rate)`` times it (white
    noise keeps the fraction of its variance below the cut-off)."""
    from .models import torque_noise

    t = data.t - data.t[0]
    dq_raw = data.dq if logged_dq else np.gradient(data.q, data.t, axis=0)
    raw_sd = torque_noise(dq_raw)
    noise = {
        "logged": raw_sd.tolist(),
        "filtered": (raw_sd * math.sqrt(min(1.0, 2.0 * fc / rate))).tolist(),
        "source": "logged velocities" if logged_dq else "central differences of the positions",
    }
    if cycle is not None:
        T = cycle["period_s"]
        sel = np.flatnonzero(t < cycle["periods"] * T * (1 - 1e-12))
        phase = np.mod(t[sel], T)
        grid = np.append(tu, T)

        def at(x):
            return CubicSpline(grid, np.vstack([x, x[:1]]), axis=0, bc_type="periodic")(phase)

        states = [at(x) for x in (qf, dqf, ddqf)]
    else:
        m = tu.shape[0]
        lo, hi = tu[drop], tu[m - drop - 1]
        tol = 1e-9 * max(abs(hi), 1.0)
        sel = np.flatnonzero((t >= lo - tol) & (t <= hi + tol))
        if sel.size == m - 2 * drop and np.array_equal(t[sel], tu[drop : m - drop]):
            states = [x[drop : m - drop] for x in (qf, dqf, ddqf)]
        else:
            states = [CubicSpline(tu, x, axis=0)(t[sel]) for x in (qf, dqf, ddqf)]
    q_s, dq_s, ddq_s = states
    return JointData(
        data.t[sel],
        q_s,
        dq_s,
        ddq_s,
        None if data.tau is None else data.tau[sel],
        source=data.source,
        processing={"velocity_noise": noise},
        units_checked=data.units_checked,
    )


class _Joined:
    """Regressor rows of several logs stacked, each filtered like its own torques."""

    def __init__(self, logs):
        self.logs = logs

    def signals(self, fn) -> np.ndarray:
        return np.concatenate(
            [
                fn(d.q, d.dq, d.ddq)
                if d.regressor_filter is None
                else d.regressor_filter.signals(fn)
                for d in self.logs
            ],
            axis=0,
        )

    def regressor(self, base) -> np.ndarray:
        parts = []
        for d in self.logs:
            if d.regressor_filter is not None:
                parts.append(d.regressor_filter.regressor(base))
            else:
                parts.append(base.regressor(d.q, d.dq, d.ddq))
        return np.concatenate(parts, axis=0)


def concatenate(logs) -> JointData:
    """Several logs (preprocessed or not) of one robot as one identification data set: samples
    stacked, the time of each log shifted to follow the one before (the samples are equations;
    no derivative is taken across the joins), regressor filters kept per log, the first sample
    of each log in ``starts`` (the integral and energy models' windows do not span a join,
    :attr:`JointData.starts`), the logged samples joined alike (``logged``) when every log has
    them. The processing
    of each log is listed under ``processing["logs"]``; ``processing["preprocess"]`` is the first
    log's, with ``"logs"`` listing every log's."""
    from .estimation import _logs

    logs = _logs(logs, "logs")
    logs = list(logs)
    if not logs:
        raise DataError("no logs to concatenate")
    n = logs[0].n
    for d in logs[1:]:
        if d.n != n:
            raise DataError(f"{d.source or 'data'} has {d.n} joints; {logs[0].source} has {n}")
    if any(d.tau is None for d in logs):
        raise DataError("every log to concatenate needs torques")
    ts, end, starts, first = [], None, [], 0
    for d in logs:
        starts += [first + s for s in (d.starts or (0,))]  # a joined log's own joins kept
        first += d.m
        step = float(np.median(np.diff(d.t))) if d.m > 1 else 1.0
        t = d.t - d.t[0] + (0.0 if end is None else end + step)
        ts.append(t)
        end = float(t[-1])
    q, dq, ddq, tau = (
        np.concatenate([getattr(d, k) for d in logs]) for k in ("q", "dq", "ddq", "tau")
    )
    out = JointData(
        np.concatenate(ts),
        q,
        dq,
        ddq,
        tau,
        source=" + ".join(d.source or "data" for d in logs),
        processing={"logs": [d.processing for d in logs]},
        starts=tuple(starts),
        units_checked=all(d.units_checked for d in logs),
    )
    pres = [d.processing.get("preprocess") for d in logs]
    if pres[0] is not None:
        out.processing["preprocess"] = {**pres[0], "logs": pres}
    if any(d.regressor_filter is not None for d in logs):
        out.regressor_filter = _Joined(logs)
    if all(d.logged is not None for d in logs):
        out.logged = concatenate([d.logged for d in logs])
    return out
