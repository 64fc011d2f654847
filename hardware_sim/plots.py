"""Pictures of experiment results (matplotlib imported lazily, no pyplot state)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hardware_sim.summary import StrategySummary

__all__ = ["plot_histograms"]


def plot_histograms(
    rows: Sequence[StrategySummary], path: str | os.PathLike[str], title: str = ""
) -> None:
    """Grouped bars: percent of trials per number of touches (Table 4.1 columns),
    one colour per strategy; written as a PNG to `path`."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from hardware_sim.summary import BINS

    fig = Figure(figsize=(9, 4.5), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    x = np.arange(len(BINS))
    width = 0.8 / max(len(rows), 1)
    for i, row in enumerate(rows):
        shares = [100 * row.histogram[b] for b in BINS]
        label = f"{row.strategy} (mean {row.mean_touches:.2f})"
        ax.bar(x + (i - (len(rows) - 1) / 2) * width, shares, width, label=label)
    ax.set_xticks(x, list(BINS))
    ax.set_xlabel("touches needed")
    ax.set_ylabel("percent of trials")
    if title:
        ax.set_title(title)
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, format="png")
