"""Do the C++ filter and the numpy peer run the same filter? A Monte Carlo over trajectories.

bench_mapmatch.py compares the three implementations on one trajectory; there the C++ filter's
mean error was 3.0 m against 2.47 m for both peers at N = 10^5 (issue 18). One trajectory cannot
tell a model difference from chance, so this script filters many seeded trajectories of the
benchmark's simulator (bench_mapmatch.simulate_trajectory, 200 s at dt = 0.5 s) with

- "cpp": indoorloc.mapmatch.ParticleMapMatcher with the benchmark's options (recovery off),
- "numpy": the numpy peer (mapmatch_numpy.NumpyMapMatcher),
- "numpy, forward only" (with --ablation): the numpy peer with every negative step (v dt + eta
  < 0) replaced by no move, the rule the C++ filter applied before issue 18,

and reports per trajectory the mean position error (unprojected weighted mean, eq. (13), as in
the benchmark), and the paired differences cpp - numpy: mean, sd, standard error, and the share
of trajectories on which the C++ filter is worse.

Run:  PYTHONPATH=python .venv/bin/python benchmarks/mapmatch_agreement.py --seeds 30 --first-seed 1000
Seeds are trajectory seeds; each filter is seeded with the same seed (different streams per
implementation, so the paired difference also contains Monte Carlo noise of the filters).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_mapmatch as bm  # noqa: E402
import mapmatch_numpy as mn  # noqa: E402


class ForwardOnlyNumpyMapMatcher(mn.NumpyMapMatcher):
    """The numpy peer with the pre-issue-18 C++ rule: a negative step leaves the particle in place."""

    def predict(self, speed_mps: float, dt_s: float):
        distance = speed_mps * dt_s + self.rng.uniform(-self.noise_halfwidth_m, self.noise_halfwidth_m,
                                                       self.num_particles)
        distance = np.maximum(distance, 0.0)
        self.s, self.d, self.u = self.network.move(self.s, self.d, self.u, distance, self.rng)


def mean_error(est: np.ndarray, truth: np.ndarray) -> float:
    """Mean over the trajectory of the Euclidean error [m]."""
    return float(np.hypot(*(est - truth).T).mean())


def run(seeds, sizes, ablation: bool) -> dict:
    from indoorloc import mapmatch

    segments, ids, _ = bm.warehouse()
    network = mn.Network(segments)
    cpp_network = mapmatch.RoadNetwork(segments, ids)
    t_steps = int(round(bm.DURATION_S / bm.DT_S))
    names = ["cpp", "numpy"] + (["numpy, forward only"] if ablation else [])
    errors = {str(n): {name: [] for name in names} for n in sizes}
    start = time.perf_counter()
    for seed in seeds:
        truth, speeds, headings = bm.simulate_trajectory(segments, t_steps, bm.DT_S, seed=seed)
        for n in sizes:
            opts = mapmatch.FilterOptions(num_particles=n, kappa=bm.KAPPA,
                                          noise_halfwidth_m=bm.NOISE_HALFWIDTH_M, seed=seed)
            opts.recovery_disagreement = 0.0  # the paper's filter, as in the benchmark
            cpp = mapmatch.ParticleMapMatcher(cpp_network, opts).run(speeds, headings, bm.DT_S)
            errors[str(n)]["cpp"].append(mean_error(cpp["weighted_mean_m"], truth))
            peer = mn.NumpyMapMatcher(network, bm.KAPPA, bm.NOISE_HALFWIDTH_M, n, seed=seed)
            errors[str(n)]["numpy"].append(mean_error(peer.run(speeds, headings, bm.DT_S), truth))
            if ablation:
                fwd = ForwardOnlyNumpyMapMatcher(network, bm.KAPPA, bm.NOISE_HALFWIDTH_M, n, seed=seed)
                errors[str(n)]["numpy, forward only"].append(mean_error(fwd.run(speeds, headings, bm.DT_S), truth))
        print(f"seed {seed}: " + "; ".join(
            f"N={n}: " + ", ".join(f"{k} {v[-1]:.2f}" for k, v in errors[str(n)].items()) for n in sizes),
            flush=True)
    summary = {}
    for n in sizes:
        per = {k: np.asarray(v) for k, v in errors[str(n)].items()}
        row = {k: {"mean": float(v.mean()), "median": float(np.median(v))} for k, v in per.items()}
        for other in names[1:]:
            diff = per["cpp"] - per[other]
            row[f"cpp - {other}"] = {
                "mean": float(diff.mean()), "sd": float(diff.std(ddof=1)),
                "se": float(diff.std(ddof=1) / np.sqrt(diff.size)),
                "median": float(np.median(diff)),
                "share_cpp_worse": float(np.mean(diff > 0)),
            }
        summary[str(n)] = row
    return {"seeds": list(map(int, seeds)), "sizes": list(sizes), "errors_m": errors, "summary": summary,
            "seconds": time.perf_counter() - start}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=30, help="number of trajectories")
    parser.add_argument("--first-seed", type=int, default=1000)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10**4, 10**5])
    parser.add_argument("--ablation", action="store_true", help="also the forward-only numpy peer")
    parser.add_argument("--json", type=Path, default=None, help="write every number here")
    args = parser.parse_args(argv)
    result = run(range(args.first_seed, args.first_seed + args.seeds), args.sizes, args.ablation)
    for n, row in result["summary"].items():
        print(f"N = {int(n):,}")
        for k, v in row.items():
            print(f"  {k}: " + ", ".join(f"{a} {b:.3f}" for a, b in v.items()))
    print(f"{result['seconds']:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
