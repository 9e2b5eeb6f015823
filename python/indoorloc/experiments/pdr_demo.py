"""PDR demo: the OpenShoe figure-8 and one PyShoe trial, estimated path over the reference."""

from __future__ import annotations

from indoorloc.registry import DemoContext, DemoSection, default_pdr_root, register_demo


@register_demo("pdr", "PDR: SHOE detector + ZUPT-aided EKF on real foot-mounted IMU data")
def demo(ctx: DemoContext) -> DemoSection:
    from indoorloc import plots
    from indoorloc.experiments import pdr_evaluate as pe
    from indoorloc.pdr import metrics
    from indoorloc.io import pdr_datasets as io

    root = default_pdr_root()
    if not root.is_dir():
        return DemoSection(markdown=f"PDR part skipped: recordings not found at {root}.")
    figure8 = io.load_openshoe(root / "openshoe_figure8" / "OpenShoeDataSet.txt")
    trials = io.list_pyshoe_trials(root / "pyshoe_vicon")
    trial = io.load_pyshoe_trial(trials[-5])
    pos8, _ = pe.zupt_ekf_method(figure8)
    pos_trial, _ = pe.zupt_ekf_method(trial)
    est = pos_trial[:, :2] * pe.PYSHOE_TRUTH_FROM_Z_UP
    aligned = metrics.align_2d(est, trial.truth_xy_m, pe.pyshoe_alignment_samples(trial))
    fig = plots.pdr_paths(pos8[:, :2], trial.name, aligned, trial.truth_xy_m, ctx.figure_path("pdr_paths"))
    loop = pe.score_closed_loop(figure8, (pos8, None))
    text = (
        f"OpenShoe figure-8 (820 Hz, 62 s): final error {loop['final_error_2d_m']:.3f} m over "
        f"{loop['path_length_2d_m']:.1f} m (OpenShoe's EKF 0.45 m). PyShoe trial {trial.name}: ARMSE "
        f"{metrics.armse(aligned, trial.truth_xy_m):.3f} m against Vicon. Full evaluation: `indoorloc pdr evaluate`."
    )
    return DemoSection(markdown=text, figures=[fig])
