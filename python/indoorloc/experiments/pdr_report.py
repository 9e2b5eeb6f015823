"""The PDR study's reports: Markdown tables of the evaluations with the peers' published figures
beside ours (:func:`markdown`), the summary of the recommended method over a JSON document of
:func:`indoorloc.experiments.pdr_json.evaluate_json` (:func:`recommended_summary_lines`), and the
comparison of the other methods that ``indoorloc pdr evaluate --compare`` prints
(:func:`comparison_report`, with the per-step covariance consistency of
:func:`covariance_coverage_summary`). The command line only prints these.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Union

import numpy as np

from indoorloc.experiments import pdr_methods
from indoorloc.experiments.pdr_json import DATASETS
from indoorloc.experiments.pdr_scoring import (
    PEER_PYSHOE,
    evaluate_closed_loops,
    evaluate_pyshoe,
    step_covariance_coverage,
)

PathLike = Union[str, Path]

#: The methods of ``indoorloc pdr evaluate --compare``, with their table titles.
COMPARISON_METHODS = (
    ("ZUPT EKF", pdr_methods.zupt_ekf_method),
    ("ZUPT EKF + RTS smoother", pdr_methods.zupt_rts_method),
    ("ZUPT EKF, per-recording SHOE threshold (PyShoe rule)", pdr_methods.zupt_adaptive_method),
    ("ZUPT EKF + RTS, per-recording SHOE threshold (PyShoe rule)", pdr_methods.zupt_adaptive_rts_method),
    ("INS-ZUPT increments, Mahony attitude (paper eq. 5, 9)", pdr_methods.ins_zupt_steps_method),
    ("ZUPT stride length + heading at stance, Mahony attitude (paper eq. 6-8)", pdr_methods.stride_heading_method),
)

#: Step-count error of paper 002's foot-mounted step detectors [% of steps]: magnetometer, gyroscope.
PAPER_STEP_DETECTOR_ERROR_PCT = (0.94, 0.2)


def _fmt(v: Any, spec: str = ".3f") -> str:
    if v is None:
        return "-"
    if isinstance(v, float) and not math.isfinite(v):
        return "-"
    return format(v, spec) if isinstance(v, (int, float)) else str(v)


def markdown(pyshoe: Optional[Dict[str, Any]] = None, closed_loops: Optional[Dict[str, Any]] = None,
             method_name: str = "indoorloc SHOE + ZUPT EKF") -> str:
    """Markdown tables of :func:`evaluate_pyshoe` / :func:`evaluate_closed_loops` results with the
    peers' published figures beside (x-io 0.082 / 0.421 m; OpenShoe EKF 0.45 m, smoother 0.37 m;
    PyShoe median 0.08 m, mean 0.38 m ARMSE)."""
    parts: List[str] = []
    if closed_loops is not None:
        parts += ["### Closed loops: final position error", "",
                  "| recording | samples | final error 2-D [m] | 3-D [m] | % of path (2-D) | "
                  "path length [m] | nominal [m] | peer | peer final error [m] |",
                  "|---|---:|---:|---:|---:|---:|---:|---|---:|"]
        for r in closed_loops["recordings"]:
            peer_name, peer_val = r["peer"] if r["peer"] else ("-", None)
            peer_txt = (" / ".join(f"{v:.3g}" for v in peer_val) if isinstance(peer_val, tuple)
                        else _fmt(peer_val, ".3g"))
            parts.append(f"| {r['recording']} | {r['n_samples']} | {_fmt(r['final_error_2d_m'])} | "
                         f"{_fmt(r['final_error_3d_m'])} | {_fmt(r['final_error_2d_pct'], '.2f')} | "
                         f"{_fmt(r['path_length_2d_m'], '.1f')} | {_fmt(r['nominal_distance_m'], '.0f')} | "
                         f"{peer_name} | {peer_txt} |")
        parts += ["", f"{method_name}: {_fmt(closed_loops.get('samples_per_s'), '.0f')} samples/s.", ""]
    if pyshoe is not None:
        parts += ["### PyShoe Vicon trials: 2-D ARMSE after start/heading alignment", "",
                  "| method | trials | median [m] | mean [m] | worst [m] | samples/s | "
                  "stride count |error| |",
                  "|---|---:|---:|---:|---:|---:|---:|"]
        sc = (f"{pyshoe['stride_count_abs_error_total']} "
              f"({pyshoe['stride_count_abs_error_pct']:.1f} %)"
              if "stride_count_abs_error_total" in pyshoe else "-")
        parts.append(f"| {method_name} | {pyshoe['n_trials']} | {_fmt(pyshoe['median_armse_m'])} | "
                     f"{_fmt(pyshoe['mean_armse_m'])} | {_fmt(pyshoe['worst_armse_m'])} | "
                     f"{_fmt(pyshoe['samples_per_s'], '.0f')} | {sc} |")
        p = PEER_PYSHOE
        parts.append(f"| {p['method']} | 42 | {p['median_armse_m']:.2f} | {p['mean_armse_m']:.2f} | "
                     f"~{p['worst_armse_m']:.0f} | ~{p['samples_per_s']:.0f} | - |")
        parts += ["", "| trial | ARMSE [m] | final error [m] | strides (truth) | detected |",
                  "|---|---:|---:|---:|---:|"]
        for r in pyshoe["trials"]:
            parts.append(f"| {r['trial']} | {_fmt(r['armse_m'])} | {_fmt(r['final_error_m'])} | "
                         f"{_fmt(r['strides_truth'], 'd')} | {_fmt(r['strides_detected'], 'd')} |")
        parts.append("")
    return "\n".join(parts)


def recommended_summary_lines(doc: Dict[str, Any]) -> List[str]:
    """Markdown summary (lines) of an :func:`~indoorloc.experiments.pdr_json.evaluate_json`
    document, per dataset: ARMSE median / mean / worst [m], final error median / worst [m],
    strides off (|detected - truth| summed, and its % of the true strides), the recordings the
    health check flagged implausible."""
    lines = [f"## Recommended method: {doc['default_method']}", "",
             "| dataset | recordings | ARMSE median / mean / worst [m] | final error median / worst [m] | "
             "strides off | flagged implausible |", "|---|---:|---|---|---:|---|"]
    by: Dict[str, List[Dict[str, Any]]] = {}
    for r in doc["recordings"]:
        by.setdefault(r["dataset"], []).append(r)
    for ds, rows in by.items():
        a = np.array([r["armse_m"] for r in rows if r["armse_m"] is not None])
        f = np.array([r["final_error_m"] for r in rows if r["final_error_m"] is not None])
        st = [(r["strides_truth"], r["strides_detected"]) for r in rows if r["strides_truth"] is not None]
        off = sum(abs(d - t) for t, d in st)
        tot = sum(t for t, _ in st)
        flagged = [r["name"] for r in rows if r["health"].get("implausible")]
        lines.append(f"| {ds} | {len(rows)} | "
                     + (f"{np.median(a):.3f} / {a.mean():.3f} / {a.max():.3f}" if a.size else "-") + " | "
                     + (f"{np.median(f):.3f} / {f.max():.3f}" if f.size else "-") + " | "
                     + (f"{off} / {tot} ({100.0 * off / max(tot, 1):.2f} %)" if st else "-") + " | "
                     + (", ".join(flagged) if flagged else "none") + " |")
    return lines + [""]


def covariance_coverage_summary(rows: Sequence[Dict[str, Any]]) -> Dict[str, float]:
    """Pooled figures of :func:`~indoorloc.experiments.pdr_scoring.step_covariance_coverage` rows
    (one per trial): ``inside_95_pct`` (% of all steps inside their 95 % ellipse, steps pooled over
    the trials; consistent: 95), the medians over trials of ``mean_d2`` (consistent: 2),
    ``final_error_m`` and ``final_sd_m`` [m]."""
    inside = sum(r["inside_95_pct"] * r["n_steps"] for r in rows) / max(1, sum(r["n_steps"] for r in rows))
    return {"inside_95_pct": float(inside),
            "median_mean_d2": float(np.median([r["mean_d2"] for r in rows])),
            "median_final_error_m": float(np.median([r["final_error_m"] for r in rows])),
            "median_final_sd_m": float(np.median([r["final_sd_m"] for r in rows]))}


def comparison_report(root: PathLike) -> Iterator[str]:
    """The text of ``indoorloc pdr evaluate --compare``, one block at a time as it is computed:
    per method of :data:`COMPARISON_METHODS` its tables on PyShoe and the closed loops, the
    covariance consistency of eq. 9 on the PyShoe trials and, when the mobgap folder is there,
    Weinberg's stride length and the lower-back step detectors against paper 002's figures.
    ValueError when the pyshoe, xio or openshoe folder is missing under ``root``."""
    from indoorloc.io import list_pyshoe_trials, load_pyshoe_trial

    root = Path(root)
    if not all((root / DATASETS[d]).is_dir() for d in ("pyshoe", "xio", "openshoe")):
        raise ValueError(f"indoorloc: argument 'compare': needs the pyshoe, xio and openshoe folders under {root}")
    for title, method in COMPARISON_METHODS:
        pyshoe = evaluate_pyshoe(root / "pyshoe_vicon", method)
        loops = evaluate_closed_loops(root, method)
        yield f"## {title}\n"
        yield markdown(pyshoe=pyshoe, closed_loops=loops, method_name=title)
        yield ""
    cov = covariance_coverage_summary([step_covariance_coverage(load_pyshoe_trial(p))
                                       for p in list_pyshoe_trials(root / "pyshoe_vicon")])
    yield "## Per-step covariance of eq. 9 (Mahony attitude, default covariance options), PyShoe trials\n"
    yield (f"Steps inside their 95 % ellipse: {cov['inside_95_pct']:.1f} % (consistent: 95 %); median mean d^2 "
           f"{cov['median_mean_d2']:.2f} (consistent: 2); median final error / final sd: "
           f"{cov['median_final_error_m']:.2f} m / {cov['median_final_sd_m']:.2f} m.\n")
    if (root / "mobgap_lowerback").is_dir():
        from indoorloc.experiments import pdr_stride_length

        yield "## Weinberg stride length (paper 002 eq. 4)\n"
        yield pdr_stride_length.markdown(pdr_stride_length.evaluate_weinberg_mobgap(root / "mobgap_lowerback"))
        det = pdr_stride_length.evaluate_step_detectors_mobgap(root / "mobgap_lowerback")
        magnetometer_pct, gyro_pct = PAPER_STEP_DETECTOR_ERROR_PCT
        yield (f"Step detectors on the lower back ({det['n_bouts']} INDIP walking bouts, "
               f"{det['reference_steps']} initial contacts): magnetometer {det['magnetometer_abs_error']} off "
               f"({det['magnetometer_pct']:.1f} %), gyroscope {det['gyro_abs_error']} off ({det['gyro_pct']:.1f} %); "
               f"paper 002 (foot): {magnetometer_pct} % and {gyro_pct} %.\n")
