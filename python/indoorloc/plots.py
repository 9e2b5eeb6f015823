"""Plots for reports and the demo (matplotlib, Agg backend). Kept at the edge: no core module
imports this file."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402



def _save(fig, path, **savefig_kwargs) -> Path:
    """Lays out ``fig``, writes it to ``path`` and closes it; returns ``Path(path)``."""
    fig.tight_layout()
    fig.savefig(path, **savefig_kwargs)
    plt.close(fig)
    return Path(path)


def resampling_variance(stats: Mapping[str, object], path: Path) -> Path:
    """Bar chart of the mean offspring-count variance per resampling scheme; saves PNG."""
    names = list(stats)
    values = [stats[n].mean_variance for n in names]
    fig, ax = plt.subplots(figsize=(5, 3.2), dpi=120)
    ax.bar(names, values, color=["#888", "#4a90d9", "#2a6", "#d94"])
    ax.set_ylabel("mean Var(offspring count)")
    ax.set_title("Resampling schemes: offspring variance")
    return _save(fig, path)


def wifi_path_result(model, result, path: Path) -> Path:
    """True vs estimated path (first run) on the map, and cumulative error E_t (median, 5-95 %)."""
    import numpy as np

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 5), dpi=120, gridspec_kw={"width_ratios": [1, 2]})
    pts = model.map.positions_m
    ax1.plot(pts[:, 0], pts[:, 1], ".", color="#bbb", label="reference points")
    ax1.plot(result.path_m[:, 0], result.path_m[:, 1], "k-o", ms=3, label="true path")
    for name, est in result.example_estimates_m.items():
        ax1.plot(est[:, 0], est[:, 1], "-", lw=1, label=name)
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_aspect("equal")
    ax1.set_ylim(-0.5, max(result.path_m[:, 1].max() + 1.0, 2.0))
    ax1.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.15))
    ax1.set_title(result.name, fontsize=8)
    t = np.arange(1, len(result.path_m))
    for name in result.errors_m:
        cum = result.cumulative(name)
        ax2.plot(t, np.median(cum, axis=0), label=name)
        ax2.fill_between(t, np.percentile(cum, 5, axis=0), np.percentile(cum, 95, axis=0), alpha=0.15)
    ax2.plot(t, np.cumsum(result.crb_m), "k--", lw=1, label="Cramér-Rao (efficient fix)")
    ax2.axhline(3.82, color="r", lw=0.8, ls=":", label="paper E_27 = 3.82 m")
    ax2.set_xlabel("step")
    ax2.set_ylabel("cumulative error E_t [m]")
    ax2.legend(fontsize=6)
    return _save(fig, path)


def error_cdfs(errors_by_method: Mapping[str, object], path: Path, xmax_m: float = 8.0,
               title: str = "") -> Path:
    """Empirical CDFs of position errors [m], one curve per method (x axis 0..xmax_m)."""
    from indoorloc.metrics import empirical_cdf

    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    for name, errors in errors_by_method.items():
        x, p = empirical_cdf(errors)
        ax.plot(x, p, label=name, lw=1.2, ls="-" if "(1 " in name else "--")
    ax.set_xlabel("error [m]")
    ax.set_ylabel("fraction of estimates")
    ax.set_xlim(0, xmax_m)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, ncol=2)
    return _save(fig, path)


def heading_offsets(rows, path: Path, method: str = "fusion_smoother") -> Path:
    """Per walk, the tracker's final heading offset against the walk's residual measured from its
    waypoints [deg] (rows: ``indoorloc fusion evaluate``'s ``heading_offsets``); the prior's
    centre is 0 (the training offset)."""
    r = [row for row in rows if method in row["final_deg"]]
    x = [row["residual_deg"] for row in r]
    y = [row["final_deg"][method] for row in r]
    fig, ax = plt.subplots(figsize=(4.6, 4.2), dpi=120)
    lim = max([20.0] + [abs(v) for v in x + y]) * 1.05
    ax.plot([-lim, lim], [-lim, lim], color="#888", lw=0.8, label="final = residual")
    ax.axhline(0.0, color="#c55", lw=0.8, ls="--", label="prior centre")
    ax.scatter(x, y, s=9, alpha=0.7, label=f"{method} ({len(r)} walks)")
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("walk's residual from its waypoints [deg]")
    ax.set_ylabel("tracker's final heading offset [deg]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def mapmatch_clouds(network, trajectory, clouds: Mapping[float, tuple], path: Path) -> Path:
    """Particle clouds at several times over the road network (paper 000, Figs. 5-8)."""
    times = sorted(clouds)
    fig, axes = plt.subplots(1, len(times), figsize=(4 * len(times), 3), dpi=110, squeeze=False)
    segs = network.segments_m
    dt = 0.1
    lo = segs[:, :2].min(axis=0).clip(max=segs[:, 2:].min(axis=0)) - 2.0
    hi = segs[:, :2].max(axis=0).clip(min=segs[:, 2:].max(axis=0)) + 2.0
    for ax, t in zip(axes[0], times):
        for s in segs:
            ax.plot([s[0], s[2]], [s[1], s[3]], color="#999", lw=1)
        pos, w = clouds[t]
        ax.scatter(pos[:, 0], pos[:, 1], s=1 + 30 * w / max(w.max(), 1e-300), c="#2a6", alpha=0.3, lw=0)
        k = max(0, int(round(t / dt)) - 1)
        truth = trajectory["start_m"] if t == 0 else trajectory["positions_m"][k]
        ax.plot(truth[0], truth[1], "r*", ms=12, label="vehicle")
        ax.set_title(f"t = {t:g} s", fontsize=9)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    axes[0][0].legend(fontsize=7, loc="upper left")
    return _save(fig, path)


def mapmatch_curves(results: Mapping[float, object], path: Path) -> Path:
    """Mean position error and P(correct segment) over time, one curve per κ_P (Figs. 3, 4)."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6), dpi=110)
    for kappa, r in results.items():
        ax1.plot(r.times_s, r.error_m.mean(axis=0), lw=1, label=f"κ_P = {kappa:g}")
        ax2.plot(r.times_s, r.correct.mean(axis=0), lw=1, label=f"κ_P = {kappa:g}")
    ax1.axhline(2.0, color="k", lw=0.6, ls=":")
    ax1.set_xlabel("time [s]")
    ax1.set_ylabel("mean position error [m]")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("P(correct segment)")
    ax2.set_ylim(0, 1)
    ax1.legend(fontsize=7)
    return _save(fig, path)


def analog_lorenz(example: Mapping[str, object], path: Path) -> Path:
    """Lorenz-63 truth and reconstructions: attractor (x-z plane) and x, y, z over time."""
    import numpy as np

    truth = np.asarray(example["truth"])
    estimates = example["estimates"]
    fig = plt.figure(figsize=(11, 4), dpi=110)
    ax = fig.add_subplot(1, 2, 1)
    ax.plot(truth[:, 0], truth[:, 2], "k-", lw=1, label="truth")
    for name, est in estimates.items():
        est = np.asarray(est)
        ax.plot(est[:, 0], est[:, 2], lw=0.8, label=name)
    ax.set_xlabel("x")
    ax.set_ylabel("z")
    ax.legend(fontsize=7)
    t = np.arange(truth.shape[0])
    for i, label in enumerate("xyz"):
        a = fig.add_subplot(3, 2, 2 * (i + 1))
        a.plot(t, truth[:, i], "k-", lw=1)
        for name, est in estimates.items():
            a.plot(t, np.asarray(est)[:, i], lw=0.8)
        if i == 0:
            obs = np.asarray(example["observations"])[:, 0]
            a.plot(t, obs, "r.", ms=3)
        a.set_ylabel(label)
    return _save(fig, path)


def pdr_paths(figure8_xy, trial_name: str, trial_xy, truth_xy, path: Path) -> Path:
    """OpenShoe figure-8 estimate, and a PyShoe trial estimate over its Vicon reference."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.5), dpi=110)
    ax1.plot(figure8_xy[:, 0], figure8_xy[:, 1], lw=1)
    ax1.plot(figure8_xy[0, 0], figure8_xy[0, 1], "go", label="start")
    ax1.plot(figure8_xy[-1, 0], figure8_xy[-1, 1], "rx", label="end")
    ax1.set_title("OpenShoe figure-8 (ZUPT EKF)", fontsize=9)
    ax1.set_aspect("equal")
    ax1.legend(fontsize=7)
    ax2.plot(truth_xy[:, 0], truth_xy[:, 1], "k-", lw=1, label="Vicon")
    ax2.plot(trial_xy[:, 0], trial_xy[:, 1], lw=1, label="ZUPT EKF")
    ax2.set_title(f"PyShoe trial {trial_name}", fontsize=9)
    ax2.set_aspect("equal")
    ax2.legend(fontsize=7)
    for ax in (ax1, ax2):
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    return _save(fig, path)


def network_gravity_line(x_m, truth_mgal, series_mgal: Mapping[str, object], path: Path) -> Path:
    """δg along one flight line: truth and each method's estimate [mGal] against East [m]."""
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(x_m, truth_mgal, "k-", lw=2.0, label="truth")
    for name, values in series_mgal.items():
        ax.plot(x_m, values, lw=1.0, label=name)
    ax.set_xlabel("East [m]")
    ax.set_ylabel("gravity disturbance [mGal]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return _save(fig, path, dpi=120)


def fusion_walk(snapshot: Mapping[str, object], path: Path) -> Path:
    """One fusion walk (experiments.fusion_synthetic.walk_snapshot): the plan, the truth, WiFi-only
    fixes, PDR-only, the unknown-start filter with its particle cloud at a few times, the
    smoothed track; and each method's error over time. Saves PNG."""
    import numpy as np

    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(13, 5), dpi=110, gridspec_kw={"width_ratios": [1.6, 1]})
    edges = np.asarray(snapshot["edges_m"])
    ax.plot(edges[:, [0, 2]].T, edges[:, [1, 3]].T, color="#555", lw=0.7)
    colours = ["#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22"]
    for c, cloud in enumerate(snapshot["clouds"]):
        xy = cloud["xy_m"]
        ax.scatter(xy[:, 0], xy[:, 1], s=1, color=colours[c % len(colours)], alpha=0.25, lw=0)
        ax.plot(*cloud["truth_m"], marker="*", ms=11, color=colours[c % len(colours)], mec="k",
                label=f"cloud at {cloud['t_s']:.0f} s")
    aps = np.asarray(snapshot["aps_m"])
    ax.plot(aps[:, 0], aps[:, 1], "^", color="#999", ms=4, label="access points")
    ax.plot(*np.asarray(snapshot["truth_m"]).T, color="k", lw=2, label="truth")
    ax.plot(*np.asarray(snapshot["wifi_fixes_m"]).T, "x", color="#ff7f0e", ms=5, label="WiFi-only fixes")
    ax.plot(*np.asarray(snapshot["pdr_only_m"]).T, color="#2ca02c", lw=1.2, label="PDR only (known start)")
    ax.plot(*np.asarray(snapshot["filter_m"]).T, color="#1f77b4", lw=1.2, label="filter (unknown start)")
    ax.plot(*np.asarray(snapshot["smoothed_m"]).T, color="#d62728", lw=1.6, ls="--", label="smoother")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"Synthetic building, walk seed {snapshot['seed']}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    series = {name: (t, e, "." if name == "wifi_only" else None) for name, (t, e) in snapshot["errors"].items()}
    return _finish_walk_figure(fig, ax_err, series, "time since start [s]", "position error [m]", True, path)


def _finish_walk_figure(fig, ax_err, series, xlabel: str, ylabel: str, log_y: bool, path: Path) -> Path:
    """The error-over-time panel of the walk figures (series: name -> (t, error, marker)), saved."""
    for name, (t, e, marker) in series.items():
        ax_err.plot(t, e, label=name, lw=1.2, marker=marker)
    ax_err.set_xlabel(xlabel)
    ax_err.set_ylabel(ylabel)
    if log_y:
        ax_err.set_yscale("log")
    ax_err.legend(fontsize=8)
    ax_err.grid(alpha=0.3)
    return _save(fig, path)


def fusion_real_walk(snapshot: Mapping[str, object], path: Path) -> Path:
    """One real walk (experiments.fusion_real.walk_snapshot) on its floor image: surveyed
    waypoints, WiFi fix centres, PDR from the first waypoint, the smoothed track from the unknown
    start and the smoother's trajectories (its posterior cloud); and each method's error at the
    waypoints over time. Saves PNG."""
    import numpy as np

    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(13, 5.5), dpi=110, gridspec_kw={"width_ratios": [1.5, 1]})
    extent = snapshot.get("extent_m")
    if snapshot.get("image_path") and extent:
        image = plt.imread(snapshot["image_path"])
        ax.imshow(image, extent=extent, origin="upper", alpha=0.6)
    edges = np.asarray(snapshot["edges_m"])
    if edges.size:
        ax.plot(edges[:, [0, 2]].T, edges[:, [1, 3]].T, color="#555", lw=0.5)
    traj = np.asarray(snapshot["trajectories_m"])
    if traj.size:
        ax.scatter(traj[:, 0::2].ravel(), traj[:, 1::2].ravel(), s=1, color="#d62728", alpha=0.05, lw=0,
                   label="smoother trajectories")
    wp = np.asarray(snapshot["waypoints_m"])
    ax.plot(wp[:, 0], wp[:, 1], "o-", color="k", ms=4, lw=1.5, label="surveyed waypoints")
    fx = np.asarray(snapshot["fix_centres_m"])
    if fx.size:
        ax.plot(fx[:, 0], fx[:, 1], "x", color="#ff7f0e", ms=5, label="WiFi fixes (kNN centre)")
    ax.plot(*np.asarray(snapshot["pdr_m"]).T, color="#2ca02c", lw=1.2, label="PDR only (known start)")
    ax.plot(*np.asarray(snapshot["smoothed_m"]).T, color="#d62728", lw=1.8, label="fused, smoothed (unknown start)")
    ax.set_aspect("equal")
    if extent:
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{snapshot['floor']}, walk {snapshot['walk']}", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    t = np.asarray(snapshot["waypoint_t_s"])
    series = {name: (t, e, ".") for name, e in snapshot["errors"].items()}
    return _finish_walk_figure(fig, ax_err, series, "time since the first waypoint [s]", "error at the waypoint [m]",
                               False, path)


def site_coverage(coverage: Mapping[str, object], path: Path, title: str = "",
                  lowo_points: object = None) -> Path:
    """Survey coverage of one floor (``fusion.Site.coverage``): distance from each walkable cell
    to the nearest fingerprint [m] (dense where small, absent where large), the plan's edges,
    the fingerprints; with ``lowo_points`` ((N, 3): x, y, error [m] of a leave-one-walk-out
    check) the expected error at those points."""
    import numpy as np

    x0, x1, y0, y1 = coverage["extent_m"]
    fig, ax = plt.subplots(figsize=(8, 6.5), dpi=110)
    im = ax.imshow(np.clip(coverage["distance_m"], 0, 20), origin="lower", extent=(x0, x1, y0, y1),
                   cmap="viridis_r", vmin=0, vmax=20, interpolation="nearest")
    fig.colorbar(im, ax=ax, shrink=0.8, label="distance to nearest fingerprint [m] (20+: absent)")
    edges = np.asarray(coverage["edges_m"])
    if edges.size:
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(edges.reshape(-1, 2, 2), colors="#444", linewidths=0.5))
    fp = np.asarray(coverage["fingerprints_m"])
    if fp.size:
        ax.plot(fp[:, 0], fp[:, 1], ".", ms=1.5, color="white", alpha=0.6, label="fingerprints")
    if lowo_points is not None and np.size(lowo_points):
        p = np.asarray(lowo_points)
        sc = ax.scatter(p[:, 0], p[:, 1], c=np.clip(p[:, 2], 0, 20), cmap="Reds", vmin=0, vmax=20, s=14,
                        edgecolors="k", linewidths=0.3, label="leave-one-walk-out error")
        fig.colorbar(sc, ax=ax, shrink=0.8, label="expected error [m] (leave one walk out)")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"survey coverage: {100 * coverage['fraction_within_5m']:.0f} % of the walkable area within 5 m")
    ax.legend(loc="upper right", fontsize=7)
    return _save(fig, path)
