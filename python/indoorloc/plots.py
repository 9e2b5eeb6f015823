"""Plots for reports and the demo (matplotlib, Agg backend). Kept at the edge: no core module
imports this file."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def resampling_variance(stats: Mapping[str, object], path: Path) -> Path:
    """Bar chart of the mean offspring-count variance per resampling scheme; saves PNG."""
    names = list(stats)
    values = [stats[n].mean_variance for n in names]
    fig, ax = plt.subplots(figsize=(5, 3.2), dpi=120)
    ax.bar(names, values, color=["#888", "#4a90d9", "#2a6", "#d94"])
    ax.set_ylabel("mean Var(offspring count)")
    ax.set_title("Resampling schemes: offspring variance")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return Path(path)
