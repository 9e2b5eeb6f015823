"""Track viewer: one self-contained HTML page (plotly, offline) showing tracks on their floor plan.

Use it to look at what the tracker did: the floor plan (walkable outline, shops), each walk's
track with its 95 % uncertainty region, the surveyed waypoints and the WiFi fixes when known, and
a time slider that moves a marker (with its own 95 % ellipse) along the track. Several walks go
into one page; a dropdown selects the walk and shows only that walk's floor.

The page is plotly's offline HTML with plotly.js inlined (about 4.8 MB): it opens from a file,
without a network, and no request leaves it. plotly is imported only when a page is written, so
``import indoorloc`` does not need it. docs/viewer.md has a screenshot and the API.

Example::

    from indoorloc.fusion.viewer import ViewerTrack, viewer_floor_from_plan, write_viewer_html
    floor = viewer_floor_from_plan(plan, 0, name="F1")
    walk = ViewerTrack("walk 1", "F1", t_s, xy_m, sd_m=sd_m)
    write_viewer_html("view.html", [floor], [walk])
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.io.atomic_file import write_text_atomic
from indoorloc.validate import integer, real_array

#: Squared Mahalanobis radius of the 95 % region of a 2-D Gaussian (chi-square, 2 dof): the same
#: region as :func:`indoorloc.fusion.region95_contains`.
_CHI2_95_2DOF = 5.991
#: Vertices of one drawn ellipse (closed).
_ELLIPSE_VERTICES = 25
#: Coordinates are written to the page in millimetres' precision (smaller file, nothing visible lost).
_DECIMALS = 3

_COLOURS = {"outline": "#f4f1e8", "outline_line": "#7a7466", "shop": "#c9c4b8", "shop_line": "#8f897b",
            "wall": "#5b564b", "track": "#1f5fbf", "region": "rgba(31, 95, 191, 0.18)",
            "waypoint": "#d62728", "fix": "#2ca02c", "marker": "#ff7f0e"}


def _error(arg: str, msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{arg}': {msg}")


@dataclass
class ViewerFloor:
    """One floor of the plan in the floor frame [m].

    name : str
        Shown on the page and referred to by :attr:`ViewerTrack.floor` (e.g. ``"F1"``).
    outlines : list of (K, 2) arrays [m]
        Outer rings of the walkable space.
    obstacles : list of (K, 2) arrays [m]
        Shops and other obstacles (drawn filled).
    walls : (M, 4) array [m] or None
        Thin walls as segments (x0, y0, x1, y1), drawn as lines.
    """

    name: str
    outlines: list
    obstacles: list = field(default_factory=list)
    walls: Optional[np.ndarray] = None


@dataclass
class ViewerTrack:
    """One walk's track, in the frame of its floor.

    name : str
        Shown in the walk selector; unique within a page.
    floor : str
        The :attr:`ViewerFloor.name` of the floor the walk is drawn on.
    t_s : (N,) array [s]
        Times of the track's samples, non-decreasing. The page shows times since ``t_s[0]``.
    xy_m : (N, 2) array [m]
        Positions.
    sd_m : (N, 2) array [m] or None
        Standard deviations of x and y; drawn as the 95 % region (ellipses of semi-axes
        2.45 sd, the union of those along the track as a band, and one around the marker).
    xy_correlation : (N,) array or None
        Correlation of x and y in [-1, 1] (default 0: axis-aligned ellipses); only with ``sd_m``.
    waypoints_t_s, waypoints_xy_m : (W,) [s] and (W, 2) [m] arrays or None
        Surveyed ground truth, when known (both or neither).
    fixes_t_s, fixes_xy_m : (F,) [s] and (F, 2) [m] arrays or None
        WiFi position fixes (e.g. the fingerprint kNN centres), when known (both or neither).
    floor_probability : (N,) array or None
        Probability that the walk is on ``floor`` at each sample, in [0, 1]; shown beside the
        slider's time.
    """

    name: str
    floor: str
    t_s: np.ndarray
    xy_m: np.ndarray
    sd_m: Optional[np.ndarray] = None
    waypoints_t_s: Optional[np.ndarray] = None
    waypoints_xy_m: Optional[np.ndarray] = None
    fixes_t_s: Optional[np.ndarray] = None
    fixes_xy_m: Optional[np.ndarray] = None
    floor_probability: Optional[np.ndarray] = None
    xy_correlation: Optional[np.ndarray] = None


def viewer_floor_from_plan(plan: Any, floor_index: int = 0, name: Optional[str] = None) -> ViewerFloor:
    """The :class:`ViewerFloor` of floor ``floor_index`` of an :class:`indoorloc.fusion.FloorPlan`.

    Parameters
    ----------
    plan : indoorloc.fusion.FloorPlan
        E.g. from :func:`indoorloc.io.load_floor_plan`; coordinates in the plan's frame [m].
    floor_index : int
        Index of the floor in the plan (0 .. plan.num_floors - 1), not the floor number.
    name : str, optional
        Default ``"floor N"`` with N the floor number.
    """
    if not all(hasattr(plan, a) for a in ("geometry", "num_floors")):
        raise TypeError(f"indoorloc: argument 'plan': expected an indoorloc.fusion.FloorPlan, got {type(plan).__name__}")
    n = int(plan.num_floors)
    if n < 1:
        raise _error("plan", "has no floors")
    floor_index = integer(floor_index, "floor_index", lo=0, hi=n - 1)
    geometry = plan.geometry(floor_index)
    if name is None:
        name = f"floor {geometry.floor}"
    walls = np.asarray(geometry.walls, float).reshape(-1, 4)
    return ViewerFloor(str(name), [np.asarray(r, float) for r in geometry.outlines],
                       [np.asarray(r, float) for r in geometry.obstacles], walls if len(walls) else None)


# ---- validation ----------------------------------------------------------------------------

def _name(value: Any, arg: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _error(arg, f"expected a non-empty string, got {value!r}")
    return value


def _rings(value: Any, arg: str) -> List[np.ndarray]:
    if value is None:
        return []
    if isinstance(value, np.ndarray) or isinstance(value, (str, bytes)):
        raise _error(arg, "expected a list of (K, 2) rings")
    try:
        items = list(value)
    except TypeError:
        raise _error(arg, f"expected a list of (K, 2) rings, got {type(value).__name__}") from None
    return [real_array(r, f"{arg}[{k}]", shape=(None, 2), min_size=6) for k, r in enumerate(items)]


def _optional(value: Any, arg: str, n: Optional[int], cols: Optional[int]) -> Optional[np.ndarray]:
    if value is None:
        return None
    return real_array(value, arg, shape=(n,) if cols is None else (n, cols))


def _check_floor(floor: Any, k: int) -> ViewerFloor:
    arg = f"floors[{k}]"
    if not isinstance(floor, ViewerFloor):
        raise TypeError(f"indoorloc: argument '{arg}': expected a ViewerFloor, got {type(floor).__name__}")
    outlines = _rings(floor.outlines, f"{arg}.outlines")
    if not outlines:
        raise _error(f"{arg}.outlines", "needs at least one ring")
    return ViewerFloor(_name(floor.name, f"{arg}.name"), outlines, _rings(floor.obstacles, f"{arg}.obstacles"),
                       _optional(floor.walls, f"{arg}.walls", None, 4))


def _check_pair(t: Any, xy: Any, arg_t: str, arg_xy: str) -> tuple:
    if (t is None) != (xy is None):
        raise _error(arg_t if t is None else arg_xy, f"given without '{arg_xy if t is None else arg_t}': give both or neither")
    if t is None:
        return None, None
    t = real_array(t, arg_t, ndim=1)
    return t, real_array(xy, arg_xy, shape=(t.size, 2))


def _check_track(track: Any, k: int, floor_names: Sequence[str]) -> ViewerTrack:
    arg = f"tracks[{k}]"
    if not isinstance(track, ViewerTrack):
        raise TypeError(f"indoorloc: argument '{arg}': expected a ViewerTrack, got {type(track).__name__}")
    name = _name(track.name, f"{arg}.name")
    if track.floor not in floor_names:
        raise _error(f"{arg}.floor", f"{track.floor!r} is not one of the floors {list(floor_names)}")
    t = real_array(track.t_s, f"{arg}.t_s", ndim=1, min_size=1)
    if np.any(np.diff(t) < 0):
        i = int(np.flatnonzero(np.diff(t) < 0)[0]) + 1
        raise _error(f"{arg}.t_s", f"must be non-decreasing, but entry {i} ({t[i]:g}) < entry {i - 1} ({t[i - 1]:g})")
    n = t.size
    xy = real_array(track.xy_m, f"{arg}.xy_m", shape=(n, 2))
    sd = _optional(track.sd_m, f"{arg}.sd_m", n, 2)
    if sd is not None and np.any(sd < 0):
        raise _error(f"{arg}.sd_m", f"entry {int(np.flatnonzero(sd < 0)[0])} is negative")
    rho = _optional(track.xy_correlation, f"{arg}.xy_correlation", n, None)
    if rho is not None and (sd is None or np.any(np.abs(rho) > 1)):
        raise _error(f"{arg}.xy_correlation", "needs sd_m" if sd is None else "entries must be in [-1, 1]")
    p = _optional(track.floor_probability, f"{arg}.floor_probability", n, None)
    if p is not None and np.any((p < 0) | (p > 1)):
        raise _error(f"{arg}.floor_probability", "entries must be in [0, 1]")
    wt, wxy = _check_pair(track.waypoints_t_s, track.waypoints_xy_m, f"{arg}.waypoints_t_s", f"{arg}.waypoints_xy_m")
    ft, fxy = _check_pair(track.fixes_t_s, track.fixes_xy_m, f"{arg}.fixes_t_s", f"{arg}.fixes_xy_m")
    return ViewerTrack(name, track.floor, t, xy, sd, wt, wxy, ft, fxy, p, rho)


def _check_sequence(value: Any, arg: str) -> list:
    if isinstance(value, (str, bytes, ViewerFloor, ViewerTrack)) or not hasattr(value, "__iter__"):
        raise TypeError(f"indoorloc: argument '{arg}': expected a list, got {type(value).__name__}")
    items = list(value)
    if not items:
        raise _error(arg, "is empty")
    return items


def _unique(names: Sequence[str], arg: str) -> None:
    seen = set()
    for k, n in enumerate(names):
        if n in seen:
            raise _error(f"{arg}[{k}].name", f"{n!r} is used twice; names must be unique")
        seen.add(n)


# ---- drawing -------------------------------------------------------------------------------

def _round(a: np.ndarray) -> list:
    return np.round(np.asarray(a, float), _DECIMALS).tolist()


def _ellipses(xy: np.ndarray, sd: np.ndarray, rho: Optional[np.ndarray]) -> np.ndarray:
    """(E, V, 2) vertices of the 95 % ellipses of the Gaussians with means ``xy`` (E, 2) [m],
    standard deviations ``sd`` (E, 2) [m] and correlations ``rho`` (E,), all counter-clockwise
    (so that plotly's non-zero fill of the joined rings shades their union evenly)."""
    angle = np.linspace(0.0, 2.0 * math.pi, _ELLIPSE_VERTICES)
    circle = np.stack([np.cos(angle), np.sin(angle)], axis=1) * math.sqrt(_CHI2_95_2DOF)  # (V, 2)
    r = np.zeros(len(xy)) if rho is None else np.clip(rho, -1.0, 1.0)
    # Cholesky factor of [[sx², r sx sy], [r sx sy, sy²]]: [[sx, 0], [r sy, sy sqrt(1 - r²)]]
    # (positive diagonal, so the circle's orientation is kept).
    sx, sy = sd[:, 0:1], sd[:, 1:2]
    ex = sx * circle[None, :, 0]
    ey = r[:, None] * sy * circle[None, :, 0] + sy * np.sqrt(1.0 - r[:, None] ** 2) * circle[None, :, 1]
    return np.stack([xy[:, 0:1] + ex, xy[:, 1:2] + ey], axis=2)


def _joined(rings: Sequence[np.ndarray]) -> tuple:
    """x and y lists of closed rings joined with None gaps (one plotly trace for many shapes)."""
    xs: list = []
    ys: list = []
    for ring in rings:
        ring = np.asarray(ring, float)
        closed = np.vstack([ring, ring[:1]]) if not np.array_equal(ring[0], ring[-1]) else ring
        xs += _round(closed[:, 0]) + [None]
        ys += _round(closed[:, 1]) + [None]
    return xs, ys


def decimate(t_s: np.ndarray, max_count: int) -> np.ndarray:
    """Indices of at most ``max_count`` samples of a non-decreasing time series ``t_s`` [s] spread
    evenly in time: for each of ``max_count`` equally spaced times the first sample at or after
    it (first and last samples always kept, duplicates merged). All indices when N <= max_count."""
    n = len(t_s)
    if n <= max_count:
        return np.arange(n)
    targets = np.linspace(t_s[0], t_s[-1], max_count)
    idx = np.clip(np.searchsorted(t_s, targets, side="left"), 0, n - 1)
    return np.unique(np.r_[0, idx, n - 1])


def _floor_traces(floor: ViewerFloor) -> List[dict]:
    xs, ys = _joined(floor.outlines)
    traces = [dict(type="scatter", x=xs, y=ys, mode="lines", fill="toself", fillcolor=_COLOURS["outline"],
                   line=dict(color=_COLOURS["outline_line"], width=1.5), name="walkable outline",
                   hoverinfo="skip", legendrank=1)]
    if floor.obstacles:
        xs, ys = _joined(floor.obstacles)
        traces.append(dict(type="scatter", x=xs, y=ys, mode="lines", fill="toself", fillcolor=_COLOURS["shop"],
                           line=dict(color=_COLOURS["shop_line"], width=1), name="shops / obstacles",
                           hoverinfo="skip", legendrank=2))
    if floor.walls is not None and len(floor.walls):
        w = floor.walls
        xs = np.c_[w[:, 0], w[:, 2], np.full(len(w), np.nan)].ravel()
        ys = np.c_[w[:, 1], w[:, 3], np.full(len(w), np.nan)].ravel()
        traces.append(dict(type="scatter", x=[None if np.isnan(v) else v for v in _round(xs)],
                           y=[None if np.isnan(v) else v for v in _round(ys)], mode="lines",
                           line=dict(color=_COLOURS["wall"], width=1), name="walls", hoverinfo="skip", legendrank=3))
    return [dict(tr, meta=f"floor:{floor.name}") for tr in traces]


def _status_text(track: ViewerTrack, i: int) -> str:
    t = track.t_s[i] - track.t_s[0]
    text = f"{track.name} · floor {track.floor} · t = {t:.1f} s"
    if track.floor_probability is not None:
        text += f" · P(on {track.floor}) = {track.floor_probability[i]:.2f}"
    return text


def _track_traces(track: ViewerTrack, max_ellipses: int) -> List[dict]:
    """The walk's traces; the last two are the slider's: the marker's 95 % ellipse (None when
    the walk has no sd_m) and the marker."""
    t_rel = _round(track.t_s - track.t_s[0])
    traces = []
    if track.sd_m is not None:
        idx = decimate(track.t_s, max_ellipses)
        rho = None if track.xy_correlation is None else track.xy_correlation[idx]
        xs, ys = _joined(list(_ellipses(track.xy_m[idx], track.sd_m[idx], rho)))
        traces.append(dict(type="scatter", x=xs, y=ys, mode="lines", fill="toself", fillcolor=_COLOURS["region"],
                           line=dict(width=0), name="95 % region", hoverinfo="skip", legendrank=10))
    traces.append(dict(type="scatter", x=_round(track.xy_m[:, 0]), y=_round(track.xy_m[:, 1]), mode="lines",
                       line=dict(color=_COLOURS["track"], width=2), name="track", customdata=t_rel,
                       hovertemplate="t = %{customdata:.1f} s<br>x = %{x:.1f} m, y = %{y:.1f} m<extra>track</extra>",
                       legendrank=11))
    t0 = track.t_s[0]
    if track.waypoints_t_s is not None:
        traces.append(dict(type="scatter", x=_round(track.waypoints_xy_m[:, 0]), y=_round(track.waypoints_xy_m[:, 1]),
                           mode="markers+lines", line=dict(color=_COLOURS["waypoint"], width=1, dash="dot"),
                           marker=dict(color=_COLOURS["waypoint"], size=8, symbol="diamond"),
                           name="surveyed waypoints", customdata=_round(track.waypoints_t_s - t0), legendrank=12,
                           hovertemplate="t = %{customdata:.1f} s<br>x = %{x:.1f} m, y = %{y:.1f} m<extra>waypoint</extra>"))
    if track.fixes_t_s is not None:
        traces.append(dict(type="scatter", x=_round(track.fixes_xy_m[:, 0]), y=_round(track.fixes_xy_m[:, 1]),
                           mode="markers", marker=dict(color=_COLOURS["fix"], size=6, symbol="x-thin-open",
                                                       line=dict(width=2, color=_COLOURS["fix"])),
                           name="WiFi fixes", customdata=_round(track.fixes_t_s - t0), legendrank=13,
                           hovertemplate="t = %{customdata:.1f} s<br>x = %{x:.1f} m, y = %{y:.1f} m<extra>WiFi fix</extra>"))
    if track.sd_m is not None:
        traces.append(dict(type="scatter", x=[], y=[], mode="lines", line=dict(color=_COLOURS["marker"], width=1.5),
                           name="95 % region at t", hoverinfo="skip", legendrank=20))
    traces.append(dict(type="scatter", x=[], y=[], mode="markers", name="position at t", legendrank=21,
                       marker=dict(color=_COLOURS["marker"], size=13, line=dict(color="white", width=2)),
                       hovertemplate="x = %{x:.1f} m, y = %{y:.1f} m<extra>position at t</extra>"))
    return [dict(tr, meta=f"walk:{track.name}") for tr in traces]


def _marker_state(track: ViewerTrack, i: int) -> tuple:
    """The slider's trace update at sample i: x and y lists for (ellipse,) marker."""
    xs, ys = [], []
    if track.sd_m is not None:
        rho = None if track.xy_correlation is None else track.xy_correlation[i:i + 1]
        ring = _ellipses(track.xy_m[i:i + 1], track.sd_m[i:i + 1], rho)[0]
        xs.append(_round(ring[:, 0]))
        ys.append(_round(ring[:, 1]))
    xs.append(_round(track.xy_m[i:i + 1, 0]))
    ys.append(_round(track.xy_m[i:i + 1, 1]))
    return xs, ys


def _bounds(track: ViewerTrack) -> tuple:
    """x and y axis ranges [m] around the walk (track and waypoints; fixes may be outliers),
    15 % margin, at least 30 m wide: the page opens on the walk; plotly's autoscale button (or a
    double click) shows the whole floor."""
    pts = [track.xy_m] + ([track.waypoints_xy_m] if track.waypoints_xy_m is not None else [])
    allp = np.vstack(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    centre, half = (lo + hi) / 2, np.maximum((hi - lo) * 0.65, 15.0)
    return [float(centre[0] - half[0]), float(centre[0] + half[0])], [float(centre[1] - half[1]), float(centre[1] + half[1])]


def _slider(track: ViewerTrack, k: int, marker_traces: List[int], max_steps: int, visible: bool) -> dict:
    """Walk k's time slider: each step moves the marker (and its ellipse) and the status line."""
    steps = []
    for i in decimate(track.t_s, max_steps):
        xs, ys = _marker_state(track, i)
        steps.append(dict(method="update", label=f"{track.t_s[i] - track.t_s[0]:.1f}",
                          args=[{"x": xs, "y": ys}, {f"annotations[{k}].text": _status_text(track, i)}, marker_traces]))
    return dict(active=0, steps=steps, visible=visible, x=0.0, len=1.0, y=-0.02, yanchor="top", pad=dict(t=40, b=10),
                currentvalue=dict(prefix="t = ", suffix=" s  (time since the walk's start)", xanchor="left",
                                  font=dict(size=14)),
                ticklen=4, minorticklen=2, name=f"time:{track.name}")


def _figure(floors: List[ViewerFloor], tracks: List[ViewerTrack], title: str, max_slider_steps: int,
            max_ellipses: int) -> dict:
    """The plotly figure (a dict): every floor's and walk's traces, one slider per walk, and the
    walk selector that shows one walk, its floor, its slider and its status line."""
    data: List[dict] = []
    floor_of_trace: List[Optional[str]] = []
    walk_of_trace: List[Optional[int]] = []
    for fl in floors:
        new = _floor_traces(fl)
        data += new
        floor_of_trace += [fl.name] * len(new)
        walk_of_trace += [None] * len(new)
    sliders, annotations = [], []
    for k, tr in enumerate(tracks):
        new = _track_traces(tr, max_ellipses)
        n_marker = 2 if tr.sd_m is not None else 1
        first = len(data)
        data += new
        floor_of_trace += [None] * len(new)
        walk_of_trace += [k] * len(new)
        marker_idx = list(range(first + len(new) - n_marker, first + len(new)))
        xs, ys = _marker_state(tr, 0)
        for j, idx in enumerate(marker_idx):
            data[idx]["x"], data[idx]["y"] = xs[j], ys[j]
        sliders.append(_slider(tr, k, marker_idx, max_slider_steps, k == 0))
        annotations.append(dict(text=_status_text(tr, 0), visible=k == 0, xref="paper", yref="paper", x=0.0, y=1.0,
                                xanchor="left", yanchor="bottom", showarrow=False, font=dict(size=14),
                                name=f"status:{tr.name}"))

    def shown(k: int) -> List[bool]:
        return [(w == k) if w is not None else (f == tracks[k].floor) for f, w in zip(floor_of_trace, walk_of_trace)]

    buttons = []
    for k, tr in enumerate(tracks):
        xr, yr = _bounds(tr)
        layout_update: Dict[str, Any] = {"xaxis.range": xr, "yaxis.range": yr, "xaxis.autorange": False,
                                         "yaxis.autorange": False}
        for j in range(len(tracks)):
            layout_update[f"sliders[{j}].visible"] = j == k
            layout_update[f"annotations[{j}].visible"] = j == k
        buttons.append(dict(method="update", label=f"{tr.name}  ({tr.floor})", args=[{"visible": shown(k)}, layout_update]))
    for idx, vis in enumerate(shown(0)):
        data[idx]["visible"] = vis
    xr, yr = _bounds(tracks[0])
    layout = dict(
        title=dict(text=title, x=0.5, xanchor="center", font=dict(size=18)),
        xaxis=dict(title=dict(text="x [m]"), range=xr, autorange=False, zeroline=False, showgrid=True,
                   gridcolor="#eeeeee", constrain="domain"),
        yaxis=dict(title=dict(text="y [m]"), range=yr, autorange=False, zeroline=False, showgrid=True,
                   gridcolor="#eeeeee", scaleanchor="x", scaleratio=1, constrain="domain"),
        plot_bgcolor="white", paper_bgcolor="white", hovermode="closest",
        legend=dict(x=1.01, y=1.0, xanchor="left", yanchor="top", bgcolor="rgba(255,255,255,0.9)",
                    bordercolor="#cccccc", borderwidth=1, font=dict(size=13)),
        margin=dict(l=70, r=20, t=110, b=40),
        sliders=sliders, annotations=annotations,
        updatemenus=[dict(type="dropdown", active=0, buttons=buttons, x=0.0, y=1.12, xanchor="left", yanchor="bottom",
                          showactive=True, direction="down", pad=dict(r=4, t=0), font=dict(size=13), name="walks")])
    layout["annotations"].append(dict(text="walk:", xref="paper", yref="paper", x=0.0, y=1.12, xanchor="right",
                                      yanchor="bottom", showarrow=False, font=dict(size=13), xshift=-6, yshift=6))
    return dict(data=data, layout=layout)


def write_viewer_html(path: Any, floors: Sequence[ViewerFloor], tracks: Sequence[ViewerTrack], *,
                      title: str = "indoorloc track viewer", max_slider_steps: int = 400,
                      max_ellipses: int = 250) -> Path:
    """Write the viewer page for ``tracks`` on ``floors`` to ``path`` (atomically: a temporary
    file in the same folder, then renamed).

    Parameters
    ----------
    path : str or os.PathLike
        The HTML file to write (its folder must exist).
    floors : sequence of ViewerFloor
        Every floor a track refers to (others are allowed); names unique.
    tracks : sequence of ViewerTrack
        At least one; names unique; each ``floor`` names one of ``floors``. The first is shown
        when the page opens.
    title : str
        The page's heading and ``<title>``.
    max_slider_steps : int
        At most this many slider positions per walk (samples spread evenly in time, see
        :func:`decimate`): each position stores the marker and its ellipse (about 0.5 kB), so
        the slider adds at most about 200 kB per walk however long the walk. The track line
        keeps every sample (about 20 B each: 1.3 MB above plotly.js' 4.8 MB for 50 000 samples).
    max_ellipses : int
        At most this many 95 % ellipses per walk make the uncertainty band (spread evenly in time).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        A bad array (shape, NaN/inf, times decreasing, probabilities outside [0, 1]), an unknown
        floor name, a duplicate name, or a missing folder: the message names the argument,
        e.g. ``tracks[1].floor``.
    ImportError
        plotly is not installed (``pip install plotly``).
    """
    floors = [_check_floor(fl, k) for k, fl in enumerate(_check_sequence(floors, "floors"))]
    _unique([fl.name for fl in floors], "floors")
    names = [fl.name for fl in floors]
    tracks = [_check_track(tr, k, names) for k, tr in enumerate(_check_sequence(tracks, "tracks"))]
    _unique([tr.name for tr in tracks], "tracks")
    title = _name(title, "title")
    max_slider_steps = integer(max_slider_steps, "max_slider_steps", lo=2, hi=100_000)
    max_ellipses = integer(max_ellipses, "max_ellipses", lo=1, hi=100_000)
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"indoorloc: argument 'path': expected a path, got {type(path).__name__}")
    path = Path(path)
    if not path.parent.is_dir():
        raise _error("path", f"folder {str(path.parent)!r} does not exist")
    try:
        import plotly.io as pio  # lazily: only the viewer needs plotly
    except ImportError as exc:
        raise ImportError("indoorloc: the track viewer needs plotly (pip install plotly)") from exc
    figure = _figure(floors, tracks, title, max_slider_steps, max_ellipses)
    config = dict(displaylogo=False, responsive=True, scrollZoom=True,
                  toImageButtonOptions=dict(format="png", filename="indoorloc_track"))
    html = pio.to_html(figure, include_plotlyjs=True, include_mathjax=False, full_html=True, config=config,
                       div_id="indoorloc-viewer", default_width="100%", default_height="99vh", validate=True)
    html = html.replace("<head>", f"<head><title>{_html_escape(title)}</title>"
                              "<style>html, body {margin: 0; padding: 0;}</style>", 1)
    write_text_atomic(path, html)
    return path


def _html_escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


__all__ = ["ViewerFloor", "ViewerTrack", "decimate", "viewer_floor_from_plan", "write_viewer_html"]
