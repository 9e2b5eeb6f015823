"""`indoorloc pdr ...` subcommands."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from indoorloc.registry import default_pdr_root


def cmd_evaluate(args: argparse.Namespace) -> int:
    from indoorloc.experiments import pdr_evaluate as pe

    root = Path(args.data_root) if args.data_root else default_pdr_root()
    if not root.is_dir():
        raise ValueError(f"indoorloc: argument 'data_root': {root} is not a folder")
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
    e = psub.add_parser("evaluate", help="SHOE + ZUPT EKF on every recording in ../shared/data/pdr", parents=[quiet_parent()])
    e.add_argument("--data-root", default=None, help="folder of the PDR datasets (default ../shared/data/pdr)")
    e.set_defaults(func=cmd_evaluate)
