"""Run every speed benchmark and write benchmarks/results/<name>.json plus results.md.

Each benchmark times indoorloc and its peers in the same process, interleaved, so that the
ratios hold on a noisy machine. Peers are installed by the `bench` extra, never at run time.
Usage: python benchmarks/run.py [--quick]
"""

from __future__ import annotations

import argparse
import importlib
import json
import platform
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHMARKS = ["bench_resampling", "bench_wifi", "bench_wifi_fix", "bench_mapmatch", "bench_analog", "bench_pdr", "bench_network",
              "bench_network_scale", "bench_fusion", "bench_fusion_grid", "bench_fusion_live",
              "bench_wifi_matcher", "bench_wifi_heading_sequence"]


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE))
    out_dir = HERE / "results"
    out_dir.mkdir(exist_ok=True)
    lines = [f"# Benchmarks ({platform.machine()}, Python {platform.python_version()})", ""]
    for name in BENCHMARKS:
        module = importlib.import_module(name)
        result = module.run(quick=args.quick)
        (out_dir / f"{name}.json").write_text(json.dumps(result, indent=2))
        lines += [f"## {result['title']}", "", module.markdown(result), ""]
    (out_dir / "results.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
