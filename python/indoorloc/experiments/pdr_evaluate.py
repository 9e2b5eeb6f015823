"""Accuracy of foot-mounted pedestrian dead reckoning on real recordings (paper 002 context).

The study is four modules, each importable on its own; every name stays importable from here:

- :mod:`~indoorloc.experiments.pdr_methods`: the methods compared, each a callable
  ``method(recording) -> positions_m (N, 3)`` or ``-> (positions_m (N, 3), stride_indices (S,))``.
  The recommended one is :func:`zupt_guard_method`, an adapter of
  :func:`indoorloc.pdr.recommended.run_recommended` (the SHOE statistic with the swing-guard
  threshold, the ZUPT EKF + RTS smoother with its health check, :func:`indoorloc.pdr.count_strides`;
  the pipeline and the metrics live in the ``indoorloc.pdr`` package). :func:`zupt_ekf_method`
  (fixed per-sensor threshold) and :func:`zupt_adaptive_method` (issue 8's per-class rule, which
  overfitted) remain for comparison.
- :mod:`~indoorloc.experiments.pdr_scoring`: :func:`evaluate_pyshoe`, the University of Toronto /
  PyShoe Vicon trials (per-sample ground truth). Each estimate is aligned with
  :func:`indoorloc.pdr.metrics.align_2d` (start position and initial heading, as PyShoe does) and
  scored by :func:`indoorloc.pdr.metrics.armse`; median, mean and worst over trials, and the
  stride count error when the method also returns its detected strides.
  :func:`evaluate_closed_loops`: the x-io short / long walks and the OpenShoe figure-8, which end
  where they start: the final position error ||p_last - p_first|| (2-D and 3-D) and its
  percentage of the distance walked (path length of the estimate).
- :mod:`~indoorloc.experiments.pdr_json`: :func:`evaluate_json` writes every recording's figures
  in the stable schema of docs/pdr.md.
- :mod:`~indoorloc.experiments.pdr_report`: :func:`markdown` renders the evaluations as tables
  with the peers' published figures beside ours; the summaries ``indoorloc pdr evaluate`` prints.

``indoorloc.pdr`` is imported lazily, so these modules import without the compiled bindings.

Examples
--------
>>> from indoorloc.experiments import pdr_evaluate as pe
>>> res = pe.evaluate_pyshoe("../shared/data/pdr/pyshoe_vicon", pe.zupt_ekf_method)  # doctest: +SKIP
>>> print(pe.markdown(pyshoe=res))  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from indoorloc.experiments.pdr_json import (
    DATASETS,
    JSON_ROW_KEYS,
    dataset_task,
    evaluate_json,
    evaluate_json_on_dask,
)
from indoorloc.experiments.pdr_methods import (
    ADAPTIVE_SHOE,
    DEFAULT_SHOE_THRESHOLD,
    Method,
    MethodOutput,
    adaptive_threshold,
    default_threshold,
    ins_zupt_steps_method,
    shoe_stance,
    stance_step_samples,
    step_positioning_method,
    stride_heading_method,
    strides_from_stance,
    with_threshold,
    zupt_adaptive_method,
    zupt_adaptive_rts_method,
    zupt_ekf_method,
    zupt_guard_method,
    zupt_rts_method,
)
from indoorloc.experiments.pdr_report import (
    COMPARISON_METHODS,
    comparison_report,
    covariance_coverage_summary,
    markdown,
    recommended_summary_lines,
)
from indoorloc.experiments.pdr_scoring import (
    PEER_CLOSED_LOOP_FINAL_ERROR_M,
    PEER_PYSHOE,
    PYSHOE_TRUTH_FROM_Z_UP,
    PathLike,
    closed_loop_recordings,
    evaluate_closed_loops,
    evaluate_pyshoe,
    evaluate_recordings,
    pyshoe_alignment_samples,
    score_closed_loop,
    score_pyshoe_trial,
    step_covariance_coverage,
    tune_threshold,
)
from indoorloc.io.pdr_datasets import ImuRecording


#: The study's names, importable from here (defined in the four modules above).
__all__ = [
    "ADAPTIVE_SHOE", "adaptive_threshold", "closed_loop_recordings", "COMPARISON_METHODS",
    "comparison_report", "covariance_coverage_summary", "dataset_task", "DATASETS",
    "DEFAULT_SHOE_THRESHOLD", "default_threshold", "evaluate_closed_loops", "evaluate_json",
    "evaluate_json_on_dask", "evaluate_pyshoe", "evaluate_recordings", "ImuRecording",
    "ins_zupt_steps_method", "JSON_ROW_KEYS", "markdown", "Method", "MethodOutput", "PathLike",
    "PEER_CLOSED_LOOP_FINAL_ERROR_M", "PEER_PYSHOE", "pyshoe_alignment_samples",
    "PYSHOE_TRUTH_FROM_Z_UP", "recommended_summary_lines", "score_closed_loop",
    "score_pyshoe_trial", "shoe_stance", "stance_step_samples", "step_covariance_coverage",
    "step_positioning_method", "stride_heading_method", "strides_from_stance", "tune_threshold",
    "with_threshold", "zupt_adaptive_method", "zupt_adaptive_rts_method", "zupt_ekf_method",
    "zupt_guard_method", "zupt_rts_method",
]


# --------------------------------------------------------------------------------------------
# Names moved into the pdr package (docs/api_changes.md): still importable from here for one
# release, with a DeprecationWarning.
# --------------------------------------------------------------------------------------------
_MOVED = {"align_2d": "indoorloc.pdr.metrics", "armse": "indoorloc.pdr.metrics",
          "path_length": "indoorloc.pdr.metrics", "run_recommended": "indoorloc.pdr.recommended",
          "detect_stance": "indoorloc.pdr.recommended", "ZUPT_DETECTOR": "indoorloc.pdr.recommended",
          "DEFAULT_METHOD": "indoorloc.pdr.recommended", "SHOE_WINDOW": "indoorloc.pdr.recommended",
          "SHOE_SIGMA_ACC_MPS2": "indoorloc.pdr.recommended", "SHOE_SIGMA_GYRO_RADPS": "indoorloc.pdr.recommended"}


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        import importlib
        import warnings

        warnings.warn(f"indoorloc.experiments.pdr_evaluate.{name} is deprecated and will be removed in the next "
                      f"release: use {_MOVED[name]}.{name} (docs/api_changes.md)", DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(_MOVED[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
