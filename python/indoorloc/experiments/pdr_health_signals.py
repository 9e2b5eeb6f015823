"""Can any IMU-only signal flag the PDR failures the health check lets through? (issue 28;
docs/errors.md, "What the health check cannot see").

Runs: the 21 PyShoe Vicon trials with the recommended detector and at fixed SHOE thresholds
1e4-1e7 (half-decade steps), as in the calibration of :mod:`indoorloc.experiments.pdr_low_motion`.
Among the runs the health check does not flag, "good" ones (ARMSE < 0.4 m) and failures
(ARMSE >= 0.4 m). For each candidate signal, physically motivated, the range over the good runs
and how many failures lie beyond the most extreme good run (what a limit that flags no good run
here could catch at best, with no margin for trials not seen):

- ``longest_over_median_swing``: a missed stance merges two swings (the EKF's swing_max_s /
  swing_median_s);
- ``onset_speed_mps``: the speed the filter had integrated when each stance began (median), a foot
  still moving when "stance" is declared;
- ``onset_speed_share``: the same over the mean swing speed (median stride / median swing);
- ``stance_motion_ratio``: as in the health check;
- ``path_gain_lower_threshold``: the path at a threshold half a decade lower over this path, minus
  one: a threshold that lets the ends of swings into stance shortens the path, so a lower one
  lengthens it;
- ``stride_count_ratio``: strides counted over strides of the gyroscope's rhythm.

``python -m indoorloc.experiments.pdr_health_signals --data-root ../shared/data/pdr`` (about 1
minute) prints the table as Markdown.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc import pdr
from indoorloc.experiments import pdr_evaluate as pe
from indoorloc.io.pdr_datasets import ImuRecording, list_pyshoe_trials, load_pyshoe_trial
from indoorloc.pdr import metrics, recommended
from indoorloc.progress import progress, set_quiet

#: Fixed thresholds of the runs (log10), as in the calibration table.
LOG_THRESHOLDS = (4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0)

#: name -> True when a failure lies above the good runs (False: below).
SIGNALS = {"longest_over_median_swing": True, "onset_speed_mps": True, "onset_speed_share": True,
           "stance_motion_ratio": True, "path_gain_lower_threshold": True, "stride_count_ratio": False}


def _path_at(rec: ImuRecording, threshold: float) -> float:
    """2-D path length [m] of the EKF + RTS with a fixed SHOE threshold."""
    det = recommended.detect_stance(rec, rule="fixed", threshold=threshold, max_threshold=10.0 * threshold)
    stance = np.asarray(det["zupt_stance"], dtype=bool)
    out = pdr.zupt_ekf(rec.time_s, rec.acc_mps2, rec.gyro_radps, stance, options=pdr.ZuptEkfOptions(smooth=True))
    return metrics.path_length(np.asarray(out["positions_m"])[:, :2])


def signals(rec: ImuRecording, label: str, **overrides: Any) -> Dict[str, Any]:
    """One run of the recommended pipeline (``overrides`` to the detector) with its ARMSE, its
    health flag and the candidate signals (module docstring)."""
    out = recommended.run_recommended(rec, **overrides)
    sc = pe.score_pyshoe_trial(rec, (out["positions_m"], out["stride_indices"]))
    h = out["health"]
    path = metrics.path_length(out["positions_m"][:, :2])
    swing, stride = float(h["swing_median_s"]), float(h["median_stride_m"])
    swing_speed = stride / swing if swing > 0 else float("nan")
    lower = _path_at(rec, float(h["shoe_threshold"]) / 10 ** 0.5)
    return {"label": label, "name": rec.name, "armse_m": sc["armse_m"], "flagged": bool(h["implausible"]),
            "longest_over_median_swing": float(h["swing_max_s"]) / swing if swing > 0 else float("nan"),
            "onset_speed_mps": float(h["speed_at_stance_median_mps"]),
            "onset_speed_share": float(h["speed_at_stance_median_mps"]) / swing_speed if swing_speed > 0 else float("nan"),
            "stance_motion_ratio": float(h["stance_motion_ratio"]),
            "path_gain_lower_threshold": lower / path - 1.0 if path > 0 else float("nan"),
            "stride_count_ratio": out["stride_indices"].size / h["rhythm_strides"] if h["rhythm_strides"] else float("nan")}


def separation(runs: Sequence[Dict[str, Any]]) -> List[Dict[str, Any]]:
    """Per signal: range over the unflagged good runs, the unflagged failures' range, and how
    many of those lie beyond every good run."""
    good = [r for r in runs if not r["flagged"] and r["armse_m"] < 0.4]
    bad = [r for r in runs if not r["flagged"] and r["armse_m"] >= 0.4]
    rows = []
    for name, above in SIGNALS.items():
        g = np.array([r[name] for r in good if np.isfinite(r[name])])
        b = np.array([r[name] for r in bad if np.isfinite(r[name])])
        edge = g.max() if above else g.min()
        beyond = int((b > edge).sum() if above else (b < edge).sum())
        rows.append({"signal": name, "good_min": float(g.min()), "good_max": float(g.max()),
                     "fail_min": float(b.min()) if b.size else float("nan"),
                     "fail_max": float(b.max()) if b.size else float("nan"), "beyond": beyond, "failures": int(b.size),
                     "good": int(g.size)})
    return rows


def markdown(rows: Sequence[Dict[str, Any]]) -> str:
    lines = ["| signal | good runs, not flagged (min..max) | failures, not flagged (min..max) | failures beyond every good run |",
             "|---|---|---|---:|"]
    for r in rows:
        lines.append(f"| {r['signal']} | {r['good_min']:.3g}..{r['good_max']:.3g} ({r['good']}) | "
                     f"{r['fail_min']:.3g}..{r['fail_max']:.3g} | {r['beyond']} of {r['failures']} |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-root", required=True, help="the shared pdr data folder")
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = ap.parse_args(argv)
    set_quiet(args.quiet)
    runs = []
    for p in progress(list_pyshoe_trials(Path(args.data_root) / "pyshoe_vicon"), desc="trials"):
        rec = load_pyshoe_trial(p)
        runs.append(signals(rec, "recommended"))
        for lg in LOG_THRESHOLDS:
            runs.append(signals(rec, f"fixed 1e{lg:g}", rule="fixed", threshold=10.0 ** lg, max_threshold=10.0 ** (lg + 1)))
    print(markdown(separation(runs)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
