#!/usr/bin/env python3
"""Python against C++ (issue 16), measured in one run on the same machine.

1. 1000 bounding-table trials of 1200 steps (data/bounding_table.wob's problem, §5.2) as one
   batched wobble.run_trials call on every core, against the C++ synthesis bench's
   BM_Trials1000/0 (synth_bench, the same RunTrials); runs alternate C++, Python, C++, ...
   The two draw their candidates from different generators, so the same batch is also timed
   against the C++ simulations inside the Python call (TrialResults.seconds).
2. The overhead of one World.step() call from Python: 10⁵ calls of step() against one call
   of step(100000) on the same kind of state (the table in the air).

    make bench-python        (or: PYTHONPATH=build/python python3 bench/python_bench.py build)
"""
import json
import pathlib
import statistics
import subprocess
import sys
import time

import numpy as np

import wobble

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "data"


def bounding_table_problem():
    interp = wobble.Interpreter()
    lines = []
    for line in (DATA / "bounding_table.wob").read_text().splitlines():
        if line.startswith("anneal"):
            break
        lines.append(line)
    interp.run("\n".join(lines), name=str(DATA / "bounding_table.wob"), dir=str(DATA))
    return interp.synthesis_problem(), interp.pose_graph


def cpp_trials_ms(build):
    out = subprocess.run([str(pathlib.Path(build) / "bench" / "synth_bench"), "--benchmark_filter=BM_Trials1000/0",
                          "--benchmark_format=json"], check=True, capture_output=True, text=True).stdout
    runs = [b for b in json.loads(out)["benchmarks"] if b["name"].startswith("BM_Trials1000/0")]
    return runs[0]["real_time"]  # ms per 1000 trials (2 iterations)


def python_trials_ms(problem, poses, durations):
    start = time.perf_counter()
    r = wobble.run_trials(problem, poses, durations, threads=0)
    ms = (time.perf_counter() - start) * 1e3
    return ms, r.seconds * 1e3, float(np.mean(r.ok))


def main(build):
    problem, graph = bounding_table_problem()
    rng = np.random.default_rng(1)
    poses = graph.poses[None] + rng.normal(0, 0.1, (1000,) + graph.poses.shape)
    cpp, py, inner, ok = [], [], [], 0.0
    for _ in range(3):
        cpp.append(cpp_trials_ms(build))
        ms, inner_ms, ok = python_trials_ms(problem, poses, graph.durations)
        py.append(ms)
        inner.append(inner_ms)
    print(f"1000 trials x {problem.steps} steps, every core:")
    print(f"  C++ synth_bench BM_Trials1000/0: median {statistics.median(cpp):8.1f} ms  (runs {', '.join(f'{x:.0f}' for x in cpp)})")
    print(f"  Python wobble.run_trials:        median {statistics.median(py):8.1f} ms  (runs {', '.join(f'{x:.0f}' for x in py)}),"
          f" {ok:.0%} of the trials ran to the end")
    print(f"  ratio Python / C++ bench: {statistics.median(py) / statistics.median(cpp):.3f}"
          " (the bench draws its 1000 candidates with std::mt19937_64, Python with numpy: same spread, other trials)")
    same = [p / i for p, i in zip(py, inner)]
    print(f"  same batch, the Python call against its own C++ simulations: median ratio {statistics.median(same):.4f}"
          f" (conversions {statistics.median([p - i for p, i in zip(py, inner)]):.2f} ms)")

    table = wobble.load_body(str(DATA / "table.obj"), [str(DATA / "table_modes.def")])
    options = wobble.WorldOptions(dt=1e-4)
    options.ground.enabled = False
    options.gravity_on = False
    world = wobble.World(options)
    world.add_body(table)
    n = 100_000
    per_call, per_step = [], []
    for _ in range(3):
        world.set_state(0, [0, 1e4, 0, 0.01, 0, 0, 0])
        start = time.perf_counter()
        for _ in range(n):
            world.step()
        per_call.append((time.perf_counter() - start) / n)
        world.set_state(0, [0, 1e4, 0, 0.01, 0, 0, 0])
        start = time.perf_counter()
        world.step(n)
        per_step.append((time.perf_counter() - start) / n)
    call, step = statistics.median(per_call), statistics.median(per_step)
    print(f"World.step() from Python: {call * 1e6:.2f} us a call; inside step(n): {step * 1e6:.2f} us a step;"
          f" overhead of a call {(call - step) * 1e6:.2f} us ({call / step:.1f}x one step)")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build"))
