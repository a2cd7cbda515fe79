"""Every figure of roe_sep, as PNG files, in the layout flight-dynamics people expect (the seeds' figures).

Modules: :mod:`.montecarlo` (the double-impulse p sweep, seed 002 Figs. 3-8), :mod:`.acceptance` (multi-impulse
AC1-AC3, seed 001 Sec. 4), :mod:`.ops` (the separation-day timeline, seed 001 Fig. 7) and :mod:`.analysis` (the
seed-003 deployment sweep and the seed-004 cluster program). Each draws with :func:`pyplot` and writes with
:func:`save`; matplotlib (headless Agg backend) is imported only when a figure is made.
"""

import numpy as np

PLOTTED_SAMPLES = 1000  # as in the seeds: all samples are simulated, 1000 are drawn for readability


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path, dpi=110):
    """Lay out, write the PNG and release the figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)


def subset(n):
    """Indices of at most :data:`PLOTTED_SAMPLES` of ``n`` samples, the same for every figure of a run."""
    return np.random.default_rng(12345).choice(n, size=min(n, PLOTTED_SAMPLES), replace=False)
