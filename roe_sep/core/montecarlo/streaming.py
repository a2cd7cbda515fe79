"""The p sweep of :mod:`~roe_sep.core.montecarlo.sweep` streamed in fixed-size blocks: constant memory at any
sample count, and the same result for every chunk size and worker count.

Random numbers: sample block ``b`` (``block`` samples, the last one shorter) draws its dispersions with
:func:`.sweep.draw` from its own generator, seeded by the child ``b`` of the run's ``numpy.random.SeedSequence``
(``SeedSequence(seed, spawn_key=(b,))``, the ``b``-th of ``SeedSequence(seed).spawn``). A block is therefore
reproducible alone, and a chunk (the unit of work: ``chunk_size / block`` consecutive blocks evaluated as one
vectorized batch) can be computed anywhere, in any order.

Evaluation: each chunk runs the per-sample physics of :mod:`~roe_sep.core.montecarlo.sweep` (:func:`~.sweep.pre_stop`,
:func:`~.sweep.after_stop`) on its draws and then :func:`~.sweep.summarize` on every block's slice, so the streamed
statistics are the same functions as the in-memory sweep. Only running statistics are kept: for every key of a
summary row, ``p_*`` fractions become integer counts (``n_*``), ``*_mean`` values sums, ``*_min``/``*_max``
extrema; histograms are integer counts on fixed bins. Counts and extrema are exact and order-free; sums are exact
(Shewchuk partials, rounded once at the end), so the chunking never changes a digit. Every probability carries the
Wilson 95 % interval of its count (:func:`.stats.wilson_interval`).
"""

import dataclasses
import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np

from ...errors import show
from ..separation.double_impulse import DoubleImpulseDesign
from .allocator import keep_freed_memory
from .stats import wilson_interval
from .sweep import Draws, MonteCarloConfig, SweepResult, after_stop, draw, pre_stop, summarize

BLOCK_SIZE = 10_000  # samples per random-number block: part of the definition of a seeded result
DEFAULT_CHUNK_SIZE = 20_000  # samples per vectorized batch: the fastest per sample here (cache), ~40 MB

# fixed histogram bins [m] (under- and overflow counted apart)
CROSSING_EDGES = np.arange(0.0, 20_001.0, 250.0)  # nearest R = 0 transit before the drift-stop
MIN_RN_EDGES = np.arange(0.0, 1_001.0, 25.0)  # minimum R-N distance after the drift-stop, Eq. (25)


def resolve_seed(seed: int | None) -> int:
    """An int seed for the run: ``seed`` itself, or fresh OS entropy when ``None`` (reported, so it can be rerun)."""
    return int(np.random.SeedSequence().entropy) if seed is None else int(seed)


def block_seed(seed: int, index: int) -> np.random.SeedSequence:
    """Child ``index`` of ``SeedSequence(seed)`` (identical to ``SeedSequence(seed).spawn(index + 1)[index]``)."""
    return np.random.SeedSequence(seed, spawn_key=(index,))


def block_count(samples: int, block: int = BLOCK_SIZE) -> int:
    """The number of random-number blocks of ``samples`` samples (the last one shorter)."""
    return -(-samples // block)


def block_draws(design: DoubleImpulseDesign, mc: MonteCarloConfig, index: int, block: int = BLOCK_SIZE) -> Draws:
    """The dispersions of block ``index`` of a run of ``mc.samples`` samples (:func:`.sweep.draw` on its seed).

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        The run's settings; ``mc.seed`` an int (:func:`resolve_seed`).
    index : int
        The block, from 0.
    block : int
        Samples per block.

    Returns
    -------
    Draws
        ``block`` samples (fewer in the last block).
    """
    size = min(block, mc.samples - index * block)
    if size < 1:
        raise ValueError(f"block {index} lies beyond {mc.samples} samples")
    return draw(design, dataclasses.replace(mc, samples=size, seed=block_seed(mc.seed, index)))


def concat_draws(parts: Sequence[Draws]) -> Draws:
    """The draws of ``parts`` one after the other."""
    return Draws(*(np.concatenate([getattr(d, f.name) for d in parts]) for f in dataclasses.fields(Draws)))


def chunk_draws(design: DoubleImpulseDesign, mc: MonteCarloConfig, first: int, count: int,
                block: int = BLOCK_SIZE) -> tuple[Draws, list[int]]:
    """(draws of blocks ``first`` to ``first + count - 1`` concatenated, their sizes).

    Parameters
    ----------
    design, mc
        As for :func:`block_draws`.
    first : int
        The first block.
    count : int
        The number of blocks.
    block : int
        Samples per block.

    Returns
    -------
    (Draws, list of int)
        The concatenated draws and the number of samples of each block.
    """
    parts = [block_draws(design, mc, b, block) for b in range(first, first + count)]
    return concat_draws(parts), [d.f1.shape[0] for d in parts]


def chunk_plan(samples: int, chunk_size: int, block: int = BLOCK_SIZE) -> list[tuple[int, int]]:
    """The chunks of a run as ``(first block, number of blocks)``; ``chunk_size`` must be a multiple of ``block``.

    Parameters
    ----------
    samples : int
        Samples of the run.
    chunk_size : int
        Samples per chunk, a positive multiple of ``block`` (ValueError otherwise).
    block : int
        Samples per random-number block.

    Returns
    -------
    list of (int, int)
        ``(first block, number of blocks)`` of each chunk, in order.
    """
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < block \
            or chunk_size % block:
        raise ValueError(f"--chunk-size must be a positive multiple of the {block}-sample random-number block, "
                         f"got {show(chunk_size)}")
    per, total = chunk_size // block, block_count(samples, block)
    return [(first, min(per, total - first)) for first in range(0, total, per)]


class ExactSum:
    """A float sum without rounding error (Shewchuk's partials, as in :func:`math.fsum`): independent of the order
    and grouping of the terms, which makes streamed means identical for every chunking."""

    def __init__(self):
        self.partials = []

    def add(self, x: float) -> None:
        """Add one term."""
        x = float(x)
        out = []
        for y in self.partials:
            if abs(x) < abs(y):
                x, y = y, x
            hi = x + y
            lo = y - (hi - x)
            if lo:
                out.append(lo)
            x = hi
        out.append(x)
        self.partials = out

    def merge(self, other: "ExactSum") -> None:
        """Add every term of ``other``."""
        for x in other.partials:
            self.add(x)

    def value(self) -> float:
        """The sum, rounded once."""
        return math.fsum(self.partials)


@dataclass
class RowStats:
    """Running statistics of the summary rows of one p (:func:`.sweep.summarize`, one call per block)."""

    p: float
    n: int = 0
    counts: dict = field(default_factory=dict)  # 'approach' -> events, from 'p_approach' (and 'n_approach')
    sums: dict = field(default_factory=dict)  # 'a_dl_mean' -> ExactSum of block mean * block size
    mins: dict = field(default_factory=dict)
    maxs: dict = field(default_factory=dict)

    def add(self, row: dict, size: int) -> None:
        """Fold in the summary of one block of ``size`` samples. ``p_X`` = k/size is a correctly rounded quotient
        of integers, so ``round(p_X * size)`` is k exactly."""
        self.n += size
        for key, value in row.items():
            if key == "p":
                continue
            if key.startswith("p_"):
                name = key[2:]
                self.counts[name] = self.counts.get(name, 0) + int(round(value * size))
            elif key.startswith("n_"):
                continue  # the same events as p_*, counted from there
            elif key.endswith("_mean"):
                self.sums.setdefault(key, ExactSum()).add(value * size)
            elif key.endswith("_min"):
                self.mins[key] = min(self.mins.get(key, math.inf), value)
            elif key.endswith("_max"):
                self.maxs[key] = max(self.maxs.get(key, -math.inf), value)
            else:
                raise ValueError(f"summary key {key!r} has no streaming rule (p_*, n_*, *_mean, *_min, *_max)")

    def merge(self, other: "RowStats") -> None:
        """Fold in the statistics of other samples of the same p."""
        self.n += other.n
        for name, k in other.counts.items():
            self.counts[name] = self.counts.get(name, 0) + k
        for key, s in other.sums.items():
            self.sums.setdefault(key, ExactSum()).merge(s)
        for key, v in other.mins.items():
            self.mins[key] = min(self.mins.get(key, math.inf), v)
        for key, v in other.maxs.items():
            self.maxs[key] = max(self.maxs.get(key, -math.inf), v)

    def row(self) -> dict:
        """The summary row of :func:`.sweep.summarize` over all samples, plus ``n_X`` and ``p_X_ci95`` for every
        probability ``p_X``."""
        out = {"p": self.p}
        for name, k in self.counts.items():
            out[f"p_{name}"] = k / self.n
            out[f"n_{name}"] = k
            out[f"p_{name}_ci95"] = list(wilson_interval(k, self.n))
        out.update({key: s.value() / self.n for key, s in self.sums.items()})
        out.update(self.mins)
        out.update(self.maxs)
        return out


def _hist(values, edges):
    counts, _ = np.histogram(values, bins=edges)
    return np.concatenate([[np.count_nonzero(values < edges[0])], counts, [np.count_nonzero(values >= edges[-1])]])


@dataclass
class SweepStats:
    """Running statistics of a streamed p sweep (everything the report needs, nothing per sample)."""

    p_values: tuple
    f1_3sigma: float
    rows: list
    n: int = 0
    crossing_min: float = math.inf
    crossing_min_3sigma: float = math.inf
    crossing_hist: np.ndarray = field(default_factory=lambda: np.zeros(CROSSING_EDGES.size + 1, dtype=np.int64))
    min_rn_hist: np.ndarray = None  # (len(p_values), bins + 2)

    @classmethod
    def empty(cls, p_values: Iterable[float], f1_3sigma: float) -> "SweepStats":
        """No sample yet for the reductions ``p_values`` [m/s]; ``f1_3sigma`` the SPL factor 3 sigma below 1."""
        ps = tuple(float(p) for p in p_values)
        return cls(ps, f1_3sigma, [RowStats(p) for p in ps],
                   min_rn_hist=np.zeros((len(ps), MIN_RN_EDGES.size + 1), dtype=np.int64))

    def merge(self, other: "SweepStats") -> "SweepStats":
        """Fold in the statistics of other samples (the same p values); returns ``self``."""
        self.n += other.n
        for mine, theirs in zip(self.rows, other.rows):
            mine.merge(theirs)
        self.crossing_min = min(self.crossing_min, other.crossing_min)
        self.crossing_min_3sigma = min(self.crossing_min_3sigma, other.crossing_min_3sigma)
        self.crossing_hist += other.crossing_hist
        self.min_rn_hist += other.min_rn_hist
        return self

    def p_best(self) -> float:
        """Minimum of P(approach) + P(evaporation) (seed 002 Table 3) on the exact counts; ties go to the smaller p."""
        rows = [r.row() for r in self.rows]
        return min((r["n_approach"] + r["n_evaporation"], r["p"]) for r in rows)[1]

    def histograms(self) -> dict:
        """The histograms as JSON: ``crossing`` and one ``min_rn`` per p, bin ``edges`` [m], ``counts``, ``below``
        and ``above``."""

        def one(edges, counts):
            return {"edges": edges.tolist(), "below": int(counts[0]), "counts": counts[1:-1].tolist(),
                    "above": int(counts[-1])}

        return {"crossing": one(CROSSING_EDGES, self.crossing_hist),
                "min_rn": [{"p": p, **one(MIN_RN_EDGES, h)} for p, h in zip(self.p_values, self.min_rn_hist)]}


def _slice(obj, sl):
    return type(obj)(**{f.name: (v[sl] if isinstance(v := getattr(obj, f.name), np.ndarray) else v)
                        for f in dataclasses.fields(obj)})


def evaluate_chunk(chunk: tuple[int, int], design: DoubleImpulseDesign, mc: MonteCarloConfig,
                   p_values: Sequence[float], block: int = BLOCK_SIZE) -> SweepStats:
    """Statistics of one chunk ``(first block, number of blocks)``: the sweep's physics on the chunk's draws, one
    :func:`.sweep.summarize` per block.

    Parameters
    ----------
    chunk : (int, int)
        ``(first block, number of blocks)`` (:func:`chunk_plan`).
    design, mc
        As for :func:`block_draws`.
    p_values : sequence of float
        The reductions [m/s].
    block : int
        Samples per random-number block.

    Returns
    -------
    SweepStats
        The chunk's running statistics.
    """
    keep_freed_memory()
    first, count = chunk
    d, sizes = chunk_draws(design, mc, first, count, block)
    f1_3s = 1.0 - 3.0 * design.config.spl_sigma
    stats = SweepStats.empty(p_values, f1_3s)
    stats.n = d.f1.shape[0]
    pre = pre_stop(design, mc, d)
    stats.crossing_min = float(np.min(pre.crossing))
    stats.crossing_min_3sigma = float(np.min(pre.crossing[d.f1 >= f1_3s], initial=np.inf))
    stats.crossing_hist = _hist(pre.crossing, CROSSING_EDGES)
    ends = np.cumsum([0] + sizes)
    for j, p in enumerate(stats.p_values):
        out = after_stop(design, mc, d, pre, p)
        stats.min_rn_hist[j] = _hist(out.min_rn, MIN_RN_EDGES)
        for lo, hi in zip(ends[:-1], ends[1:]):
            stats.rows[j].add(summarize(design, mc, p, _slice(out, slice(lo, hi))), int(hi - lo))
    return stats


def serial_map(fn: Callable, items: Iterable, *args) -> Iterator:
    """The in-process mapper: ``fn(item, *args)`` for each item, lazily, in order."""
    for item in items:
        yield fn(item, *args)


def stream_sweep(design: DoubleImpulseDesign, mc: MonteCarloConfig, p_values: Iterable[float],
                 chunk_size: int = DEFAULT_CHUNK_SIZE, block: int = BLOCK_SIZE, *, mapper: Callable = serial_map,
                 on_chunk: Callable[[int], object] | None = None) -> SweepStats:
    """The p sweep of ``mc.samples`` samples in chunks of ``chunk_size``, reduced in chunk order.

    ``mapper(fn, chunks, *args)`` yields ``fn(chunk, *args)`` in the order of ``chunks`` (serial by default; the
    engine's Dask map distributes it); ``on_chunk(samples_done_in_this_chunk)`` is called after each (progress).
    ``mc.seed`` must already be an int (:func:`resolve_seed`).

    Parameters
    ----------
    design, mc
        As for :func:`block_draws`.
    p_values : iterable of float
        The reductions [m/s], finite and non-negative.
    chunk_size : int
        Samples per chunk (:func:`chunk_plan`).
    block : int
        Samples per random-number block.
    mapper : callable
        ``mapper(fn, chunks, *args)``, yielding the results in chunk order.
    on_chunk : callable, optional
        Called with the number of samples of each chunk done.

    Returns
    -------
    SweepStats
        The statistics of all samples.
    """
    mc.validate()
    ps = tuple(float(p) for p in p_values)
    if not ps or not all(np.isfinite(p) and p >= 0 for p in ps):
        raise ValueError(f"p values must be a non-empty list of finite non-negative numbers [m/s], "
                         f"got {show(p_values)}")
    plan = chunk_plan(mc.samples, chunk_size, block)
    total = SweepStats.empty(ps, 1.0 - 3.0 * design.config.spl_sigma)
    for part in mapper(evaluate_chunk, plan, design, mc, ps, block):
        total.merge(part)
        if on_chunk is not None:
            on_chunk(part.n)
    return total


def report(stats: SweepStats, mc: MonteCarloConfig, chunk_size: int, block: int = BLOCK_SIZE) -> dict:
    """The JSON of ``roe-sep mc``: every key of :meth:`.sweep.SweepResult.to_dict` plus counts, intervals,
    histograms and the chunking.

    Parameters
    ----------
    stats : SweepStats
        :func:`stream_sweep`'s result.
    mc : MonteCarloConfig
        The run's settings (seed, drag, J2, dB).
    chunk_size, block : int
        The chunking, reported.

    Returns
    -------
    dict
        The report (SI; probabilities with their ``_ci95``).
    """
    return {
        "samples": stats.n,
        "seed": mc.seed,
        "drag": mc.drag,
        "j2": mc.j2,
        "delta_b": mc.delta_b,
        "rows": [r.row() for r in stats.rows],
        "p_best": stats.p_best(),
        "crossing_min": stats.crossing_min,
        "crossing_min_within_3sigma_f1": stats.crossing_min_3sigma if math.isfinite(stats.crossing_min_3sigma)
        else None,
        "f1_3sigma": stats.f1_3sigma,
        "block_size": block,
        "chunk_size": chunk_size,
        "histograms": stats.histograms(),
    }


def in_memory_result(design: DoubleImpulseDesign, mc: MonteCarloConfig, stats: SweepStats,
                     block: int = BLOCK_SIZE) -> SweepResult:
    """A :class:`.sweep.SweepResult` holding every sample of the streamed run (the same block draws), for the
    figures; memory grows with ``mc.samples``.

    Parameters
    ----------
    design, mc
        As for :func:`block_draws`.
    stats : SweepStats
        The streamed statistics (its p values and rows).
    block : int
        Samples per random-number block.

    Returns
    -------
    SweepResult
        Every sample's outcome per p.
    """
    d, _ = chunk_draws(design, mc, 0, block_count(mc.samples, block), block)
    pre = pre_stop(design, mc, d)
    outcomes = {p: after_stop(design, mc, d, pre, p) for p in stats.p_values}
    return SweepResult(design, mc, d, pre, [r.row() for r in stats.rows], outcomes, stats.p_best())
