"""The Monte Carlo as a straightforward per-sample loop: the baseline the vectorized sweep is measured against.

Same physics, same draws, one sample at a time through the same core functions.
"""

import numpy as np

from roe_sep.core.montecarlo.sweep import Draws, after_stop, pre_stop, summarize


def _one(d: Draws, i):
    return Draws(d.f1[i : i + 1], d.f2[i : i + 1], d.eps1[i : i + 1], d.eps2[i : i + 1], d.db_factor[i : i + 1])


def sweep_per_sample(design, mc, draws, p_values):
    """Rows like :func:`roe_sep.core.montecarlo.sweep.sweep`, computed sample by sample; returns (rows, outcomes)."""
    n = draws.f1.shape[0]
    per_p = {p: [] for p in p_values}
    crossings = np.empty(n)
    for i in range(n):
        one = _one(draws, i)
        pre = pre_stop(design, mc, one)
        crossings[i] = pre.crossing[0]
        for p in p_values:
            per_p[p].append(after_stop(design, mc, one, pre, p))
    rows, outcomes = [], {}
    for p in p_values:
        outs = per_p[p]
        merged = type(outs[0])(*(np.concatenate([getattr(o, f) for o in outs]) for f in outs[0].__dataclass_fields__))
        outcomes[p] = merged
        rows.append(summarize(design, mc, p, merged))
    return rows, outcomes, crossings
