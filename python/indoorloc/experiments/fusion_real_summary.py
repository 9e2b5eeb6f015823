"""The output of ``indoorloc fusion evaluate`` (:mod:`indoorloc.experiments.fusion_real`): the
JSON contract from the walk scores (:func:`summarize`, docs/fusion_real.md) and its Markdown
tables (:func:`markdown`)."""

from __future__ import annotations

import math
from typing import Any, Dict, List, Sequence

import numpy as np

from indoorloc.experiments.fusion_real_settings import METHODS, SELECT_OBJECTIVE, RealSettings, WalkScore
from indoorloc.experiments.fusion_real_walk import _wrap
from indoorloc.fusion import floor_evidence


def _stats(errors: np.ndarray) -> Dict[str, float]:
    return {"mean_m": float(np.mean(errors)), "median_m": float(np.median(errors)),
            "p90_m": float(np.percentile(errors, 90)), "n_waypoints": int(errors.size)}


#: Survey-coverage classes: distance from a test waypoint to the nearest training scan [m].
COVERAGE_CLASSES = (("within_5m", 0.0, 5.0), ("5_to_10m", 5.0, 10.0), ("beyond_10m", 10.0, math.inf))


def _extra_stats(scores: Sequence[WalkScore], name: str) -> Dict[str, Any]:
    """The keys added beside issue 15's (docs/fusion_real.md): ``first_10s_mean_m`` (mean error
    at waypoints in the walk's first 10 s), ``by_coverage`` (stats per coverage class),
    ``region95_coverage`` (fraction of waypoints in the estimate's 95 % ellipse, methods with a
    covariance), ``offset_error_deg`` (mean and median |final heading offset - the walk's
    residual|, methods with an offset state)."""
    sel = [s for s in scores if name in s.errors_m]
    e = np.concatenate([s.errors_m[name] for s in sel])
    t = np.concatenate([s.t_s for s in sel])
    out: Dict[str, Any] = {"first_10s_mean_m": float(e[t < 10.0].mean()) if (t < 10.0).any() else None}
    cov = [s.coverage_m if s.coverage_m is not None else np.full(s.t_s.size, np.nan) for s in sel]
    c = np.concatenate(cov)
    out["by_coverage"] = {}
    for key, lo, hi in COVERAGE_CLASSES:
        m = (c >= lo) & (c < hi)
        out["by_coverage"][key] = _stats(e[m]) if m.any() else None
    inside = [s.in_region95[name] for s in sel if name in s.in_region95]
    if inside:
        out["region95_coverage"] = float(np.concatenate(inside).mean())
    off = np.array([s.offset_error_rad[name] for s in sel if name in s.offset_error_rad])
    if off.size:
        out["offset_error_deg"] = {"mean_abs": float(np.degrees(np.abs(off)).mean()),
                                   "median_abs": float(np.degrees(np.median(np.abs(off)))), "n_walks": int(off.size)}
    return out


#: Bins of the time since the walk's first waypoint for "error against time" [s].
TIME_BINS_S = (0.0, 10.0, 20.0, 30.0, 45.0, math.inf)


def summarize(scores: Sequence[WalkScore], settings: RealSettings, seconds: float) -> dict:
    """The JSON contract of ``indoorloc fusion evaluate`` (docs/fusion_real.md):
    ``{"methods": {NAME: {"mean_m", "median_m", "p90_m", "n_waypoints"}}, "waypoints": [{"floor",
    "walk", "method", "t_s", "error_m"}], "settings": {...}}`` plus informative extras:
    ``per_floor``, ``error_vs_time`` (mean error per bin of time since the walk's start),
    ``floor_identification`` (accuracy when the floor is not given), ``seconds``,
    ``mean_seconds_per_walk``."""
    methods, per_floor, rows, by_time = {}, {}, [], {}
    for name in METHODS:
        e = [s.errors_m[name] for s in scores if name in s.errors_m]
        if not e:
            continue
        methods[name] = _stats(np.concatenate(e))
        methods[name].update(_extra_stats(scores, name))
        for fl in sorted({s.floor for s in scores}):
            ef = [s.errors_m[name] for s in scores if s.floor == fl and name in s.errors_m]
            if ef:
                per_floor.setdefault(fl, {})[name] = _stats(np.concatenate(ef))
                inside = [s.in_region95[name] for s in scores if s.floor == fl and name in s.in_region95]
                if inside:  # the 85-97 % goal holds per floor too
                    per_floor[fl][name]["region95_coverage"] = float(np.concatenate(inside).mean())
        t = np.concatenate([s.t_s for s in scores if name in s.errors_m])
        ev = np.concatenate(e)
        bins = []
        for lo, hi in zip(TIME_BINS_S[:-1], TIME_BINS_S[1:]):
            sel = (t >= lo) & (t < hi)
            bins.append({"from_s": lo, "to_s": None if math.isinf(hi) else hi, "n_waypoints": int(sel.sum()),
                         "mean_m": float(ev[sel].mean()) if sel.any() else None})
        by_time[name] = bins
    for s in scores:
        for name, e in s.errors_m.items():
            if name.startswith("_"):  # the alternatives kept for --select
                continue
            for t, v in zip(s.t_s, e):
                rows.append({"floor": s.floor, "walk": s.walk, "method": name, "t_s": round(float(t), 3),
                             "error_m": round(float(v), 4)})
    walk_seconds = {}
    for name in tuple(METHODS) + ("floor_identification",):
        v = [s.seconds[name] for s in scores if name in s.seconds]
        if v:
            walk_seconds[name] = float(np.mean(v))
    live_walks = [s for s in scores if "fusion_live" in s.errors_m]
    if "fusion_live" in methods and live_walks:
        first = np.array([s.live_first_position_s for s in live_walks], float)
        methods["fusion_live"]["first_position"] = {
            "median_s": float(np.median(first)), "p90_s": float(np.percentile(first, 90)),
            "max_s": float(first.max()),
            "waypoints_before": int(sum(s.live_waypoints_before_position for s in live_walks)),
            "walks_never_located": int(sum(1 for s in scores if "fusion_unknown_start" in s.errors_m
                                           and "fusion_live" not in s.errors_m))}
    out = {"methods": methods, "waypoints": rows, "settings": settings.to_dict(), "per_floor": per_floor,
           "error_vs_time": by_time, "seconds": round(seconds, 2), "mean_seconds_per_walk": walk_seconds}
    # Per walk: the final heading offset of each method with an offset state against the walk's
    # residual measured from its waypoints (both relative to the training yaw offset) [deg].
    out["heading_offsets"] = [
        {"floor": s.floor, "walk": s.walk, "residual_deg": round(math.degrees(s.heading_residual_rad), 3),
         "final_deg": {name: round(math.degrees(_wrap(s.heading_residual_rad + err)), 3)
                       for name, err in s.offset_error_rad.items() if name != "fusion_no_heading_offset"}}
        for s in scores if s.heading_residual_rad is not None and math.isfinite(s.heading_residual_rad)]
    ident = [s for s in scores if s.floor_correct is not None]
    if ident:
        correct = np.concatenate([s.floor_correct for s in ident])
        free = np.concatenate([s.floor_free_errors_m for s in ident])
        out["floor_identification"] = {
            "accuracy": float(correct.mean()), "n_waypoints": int(correct.size),
            "walks_all_correct": int(sum(bool(s.floor_correct.all()) for s in ident)), "n_walks": len(ident),
            "per_floor": {fl: float(np.concatenate([s.floor_correct for s in ident if s.floor == fl]).mean())
                          for fl in sorted({s.floor for s in ident})},
            # Position error of that run where the floor was right (the floor-given default is fusion_smoother).
            "mean_m_where_floor_correct": float(np.nanmean(free)) if np.isfinite(free).any() else None,
        }
        # The calibrated floor probability each walk was given against how often it was right
        # (fusion.floor_evidence.FloorCalibration; grid engine only).
        rated = [s for s in ident if s.floor_probability is not None]
        if rated:
            p = np.array([s.floor_probability for s in rated])
            right = np.array([bool(s.floor_correct.all()) for s in rated])
            out["floor_identification"]["reliability"] = {
                "mean_reported": float(p.mean()), "fraction_right": float(right.mean()),
                "bins": floor_evidence.reliability_table(p, right)}
    return out

def _coverage_lines(result: dict) -> List[str]:
    """The mean error per survey-coverage class (``by_coverage``), every method, pooled."""
    names = [n for n, m in result["methods"].items() if m.get("by_coverage")]
    if not names:
        return []
    first = result["methods"][names[0]]["by_coverage"]
    heads = [f"{label} ({(first.get(key) or {}).get('n_waypoints', 0)})"
             for key, label in (("within_5m", "<= 5 m"), ("5_to_10m", "5-10 m"), ("beyond_10m", "> 10 m"))]
    out = ["", "Mean error [m] by survey coverage (distance from the test waypoint to the nearest training scan; "
               "waypoints in brackets):", "", "| method | " + " | ".join(heads) + " |", "|---|---|---|---|"]
    for name in names:
        b = result["methods"][name]["by_coverage"]
        out.append(f"| {name} | " + " | ".join("-" if not b.get(k) else f"{b[k]['mean_m']:.2f}"
                                               for k in ("within_5m", "5_to_10m", "beyond_10m")) + " |")
    return out


def _offset_lines(rows: Sequence[dict]) -> List[str]:
    """The final heading offset against the walk's residual (``heading_offsets``): per method the
    mean and p90 of |final - residual| [deg] beside |residual| (the error of keeping the prior's 0)."""
    if not rows:
        return []
    residual = np.abs([r["residual_deg"] for r in rows])
    names = sorted({n for r in rows for n in r["final_deg"]})
    out = ["", "Final heading offset against the residual measured from the waypoints (per walk, relative to the "
               "training yaw offset) [deg]:", "", "| | walks | mean abs error | p90 abs error |", "|---|---|---|---|",
           f"| prior (offset 0) | {residual.size} | {residual.mean():.1f} | {np.percentile(residual, 90):.1f} |"]
    for name in names:
        e = np.abs([_wrap_deg(r["final_deg"][name] - r["residual_deg"]) for r in rows if name in r["final_deg"]])
        out.append(f"| {name} | {e.size} | {e.mean():.1f} | {np.percentile(e, 90):.1f} |")
    return out


def _wrap_deg(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


def _loader_lines(loader: Dict[str, dict]) -> List[str]:
    """What the loader skipped or dropped (``loader``), one line."""
    if not loader:
        return []
    parts = []
    for fl, rep in loader.items():
        dropped = ", ".join(f"{k} x{v}" for k, v in (rep.get("dropped_fields") or {}).items())
        parts.append(f"{fl} {rep.get('n_loaded', 0)} of {rep.get('n_walks', 0)} loaded"
                     + (f", {rep['n_walks_with_dropped_fields']} with fields dropped ({dropped})"
                        if rep.get("n_walks_with_dropped_fields") else ""))
    warnings = sum(int(rep.get("n_warnings", 0)) for rep in loader.values())
    return ["", f"Loader: {'; '.join(parts)}; {warnings} warning(s)."]


def markdown(result: dict) -> str:
    lines = ["| method | mean [m] | median [m] | p90 [m] | waypoints |", "|---|---|---|---|---|"]
    for name, m in result["methods"].items():
        lines.append(f"| {name} | {m['mean_m']:.2f} | {m['median_m']:.2f} | {m['p90_m']:.2f} | {m['n_waypoints']} |")
    lines += ["", "Per floor (mean / median / p90 [m]):", "",
              "| method | " + " | ".join(result["per_floor"]) + " |", "|---|" + "---|" * len(result["per_floor"])]
    for name in result["methods"]:
        cells = []
        for fl, m in result["per_floor"].items():
            s = m.get(name)
            cells.append(f"{s['mean_m']:.1f} / {s['median_m']:.1f} / {s['p90_m']:.1f}" if s else "-")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    bins = next(iter(result["error_vs_time"].values()), [])
    if bins:
        heads = [f"{b['from_s']:.0f}-{b['to_s']:.0f} s" if b["to_s"] is not None else f">= {b['from_s']:.0f} s" for b in bins]
        lines += ["", "Mean error [m] against time since the walk's first waypoint:", "",
                  "| method | " + " | ".join(heads) + " |", "|---|" + "---|" * len(heads)]
        for name, bs in result["error_vs_time"].items():
            lines.append(f"| {name} | " + " | ".join("-" if b["mean_m"] is None else f"{b['mean_m']:.1f}" for b in bs) + " |")
    lines += _coverage_lines(result)
    covered = [name for name in ("fusion_unknown_start", "fusion_live", "fusion_smoother", "fusion_known_start")
               if any("region95_coverage" in m.get(name, {}) for m in result["per_floor"].values())]
    if covered:
        lines += ["", "Share of waypoints inside the estimate's 95 % region (goal 85-97 %), pooled and per floor:", "",
                  "| method | pooled | " + " | ".join(result["per_floor"]) + " |",
                  "|---|---|" + "---|" * len(result["per_floor"])]
        for name in covered:
            cells = [f"{100 * m[name]['region95_coverage']:.1f}" if "region95_coverage" in m.get(name, {}) else "-"
                     for m in result["per_floor"].values()]
            pooled = result["methods"][name].get("region95_coverage")
            lines.append(f"| {name} | {'-' if pooled is None else f'{100 * pooled:.1f}'} | " + " | ".join(cells) + " |")
    fp = result["methods"].get("fusion_live", {}).get("first_position")
    if fp:
        lines += ["", f"Live tracker (fusion_live: causal steps, each WiFi fix applied when its scan exists): first "
                  f"position {fp['median_s']:.1f} s after the walk's first waypoint (median; p90 {fp['p90_s']:.1f} s, "
                  f"max {fp['max_s']:.1f} s); the {fp['waypoints_before']} waypoints before it are scored with that "
                  f"first position; {fp['walks_never_located']} walk(s) never located (not scored)."]
    fi = result.get("floor_identification")
    if fi:
        lines += ["", f"Floor identification (floor not given, {SELECT_OBJECTIVE} on all floors' plans and fixes): "
                  f"{100 * fi['accuracy']:.1f} % of {fi['n_waypoints']} waypoints, {fi['walks_all_correct']} of "
                  f"{fi['n_walks']} walks right throughout; per floor "
                  + ", ".join(f"{k} {100 * v:.1f} %" for k, v in fi["per_floor"].items()) + "."]
        rel = fi.get("reliability")
        if rel:
            lines[-1] += (f" Calibrated floor probability reported: {rel['mean_reported']:.3f} on average over walks, "
                          f"right {100 * rel['fraction_right']:.1f} % of the time.")
    lines += _offset_lines(result.get("heading_offsets") or [])
    lines += _loader_lines(result.get("loader") or {})
    lines.append("")
    lines.append(f"{len({(w['floor'], w['walk']) for w in result['waypoints']})} walks in {result['seconds']:.0f} s.")
    return "\n".join(lines)
