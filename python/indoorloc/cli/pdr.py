"""`indoorloc pdr ...` subcommands."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from indoorloc.registry import default_pdr_root


def _summary_lines(doc: dict) -> list:
    """Markdown summary of an evaluate_json document (recommended method)."""
    lines = [f"## Recommended method: {doc['default_method']}", "",
             "| dataset | recordings | ARMSE median / mean / worst [m] | final error median / worst [m] | "
             "strides off | flagged implausible |", "|---|---:|---|---|---:|---|"]
    by: dict = {}
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


def cmd_evaluate(args: argparse.Namespace) -> int:
    import json

    from indoorloc.experiments import pdr_evaluate as pe

    root = Path(args.data_root) if args.data_root else default_pdr_root()
    if not root.is_dir():
        raise ValueError(f"indoorloc: argument 'data_root': {root} is not a folder")
    doc = pe.evaluate_json_on_dask(root, args.only, args.scheduler) if args.scheduler else pe.evaluate_json(root, only=args.only)
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=1) + "\n")
    print("\n".join(_summary_lines(doc)))
    if not args.compare:
        return 0
    if not all((root / pe.DATASETS[d]).is_dir() for d in ("pyshoe", "xio", "openshoe")):
        raise ValueError(f"indoorloc: argument 'compare': needs the pyshoe, xio and openshoe folders under {root}")
    methods = (("ZUPT EKF", pe.zupt_ekf_method), ("ZUPT EKF + RTS smoother", pe.zupt_rts_method),
               ("ZUPT EKF, per-recording SHOE threshold (PyShoe rule)", pe.zupt_adaptive_method),
               ("ZUPT EKF + RTS, per-recording SHOE threshold (PyShoe rule)", pe.zupt_adaptive_rts_method),
               ("INS-ZUPT increments, Mahony attitude (paper eq. 5, 9)", pe.ins_zupt_steps_method),
               ("ZUPT stride length + heading at stance, Mahony attitude (paper eq. 6-8)", pe.stride_heading_method))
    for title, method in methods:
        pyshoe = pe.evaluate_pyshoe(root / "pyshoe_vicon", method)
        loops = pe.evaluate_closed_loops(root, method)
        print(f"## {title}\n")
        print(pe.markdown(pyshoe=pyshoe, closed_loops=loops, method_name=title))
        print()
    from indoorloc.io import list_pyshoe_trials, load_pyshoe_trial

    cov_rows = [pe.step_covariance_coverage(load_pyshoe_trial(p)) for p in list_pyshoe_trials(root / "pyshoe_vicon")]
    inside = sum(r["inside_95_pct"] * r["n_steps"] for r in cov_rows) / max(1, sum(r["n_steps"] for r in cov_rows))
    print("## Per-step covariance of eq. 9 (Mahony attitude, default covariance options), PyShoe trials\n")
    print(f"Steps inside their 95 % ellipse: {inside:.1f} % (consistent: 95 %); median mean d^2 "
          f"{np.median([r['mean_d2'] for r in cov_rows]):.2f} (consistent: 2); median final error / final sd: "
          f"{np.median([r['final_error_m'] for r in cov_rows]):.2f} m / {np.median([r['final_sd_m'] for r in cov_rows]):.2f} m.\n")
    if (root / "mobgap_lowerback").is_dir():
        from indoorloc.experiments import pdr_stride_length as ps

        print("## Weinberg stride length (paper 002 eq. 4)\n")
        print(ps.markdown(ps.evaluate_weinberg_mobgap(root / "mobgap_lowerback")))
        det = ps.evaluate_step_detectors_mobgap(root / "mobgap_lowerback")
        print(f"Step detectors on the lower back ({det['n_bouts']} INDIP walking bouts, "
              f"{det['reference_steps']} initial contacts): magnetometer {det['magnetometer_abs_error']} off "
              f"({det['magnetometer_pct']:.1f} %), gyroscope {det['gyro_abs_error']} off ({det['gyro_pct']:.1f} %); "
              f"paper 002 (foot): 0.94 % and 0.2 %.\n")
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("pdr", help="pedestrian dead reckoning, foot-mounted IMU (paper 002)")
    psub = p.add_subparsers(dest="pdr_command", required=True)
    e = psub.add_parser("evaluate", help="ZUPT EKF + RTS with the adaptive zero-velocity detector on every recording in ../shared/data/pdr", parents=[quiet_parent()])
    e.add_argument("--data-root", default=None, help="folder of the PDR datasets (default ../shared/data/pdr)")
    e.add_argument("--json", default=None, metavar="FILE",
                   help="write every recording's figures and health check as JSON (schema in docs/pdr.md)")
    e.add_argument("--only", nargs="+", default=None, choices=["pyshoe", "xio", "openshoe", "mobgap"],
                   help="evaluate only these datasets (default: every one present under the data root)")
    e.add_argument("--compare", action="store_true",
                   help="also print the comparison tables of the other methods (fixed and per-class thresholds, "
                        "paper 002's step-wise positioning, Weinberg on mobgap)")
    e.add_argument("--scheduler", default=None,
                   help="one Dask task per dataset on this scheduler (tcp://host:8786; the workers must see --data-root)")
    e.set_defaults(func=cmd_evaluate)
