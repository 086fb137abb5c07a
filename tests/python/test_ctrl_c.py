"""Ctrl-C from Python: long C++ loops run without the GIL and still stop at a SIGINT, raising
KeyboardInterrupt (steps, simulate, rollouts, fits) or returning the best so far (anneal)."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

SETUP = """
import sys, time
import numpy as np
import wobble
d = sys.argv[1]
table = wobble.load_body(d + '/table.obj', [d + '/table_modes.def'])
options = wobble.WorldOptions(dt=1e-5)
options.ground.enabled = False
world = wobble.World(options)
world.add_body(table)
world.set_state(0, [0, 1e6, 0, 0.1, 0, 0, 0])


def bounding_table():  # data/bounding_table.wob up to its anneal: the synthesis problem
    interp = wobble.Interpreter()
    lines = []
    for line in open(d + '/bounding_table.wob').read().splitlines():
        if line.startswith('anneal'):
            break
        lines.append(line)
    interp.run('\\n'.join(lines), dir=d)
    return interp


print('ready', flush=True)
start = time.time()
"""


def interrupted(body, data):
    """Runs SETUP + body in a child, sends SIGINT 1 s after it is ready; returns its output."""
    code = SETUP + textwrap.dedent(body)
    p = subprocess.Popen([sys.executable, "-c", code, str(data)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=dict(os.environ))
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    return out, err, time.time() - sent


@pytest.mark.parametrize("call", ["world.step(10**9)", "world.run_until(1e9)",
                                  "wobble.simulate(world, 1e4, every=1000, max_steps=10**10)",
                                  "wobble.rollout(table, np.tile(world.q(0), (2, 1)), steps=10**8, options=options,"
                                  " every=10**6, max_steps=10**10)"])
def test_a_long_loop_stops_at_ctrl_c(data, call):
    out, err, after = interrupted(f"""
        try:
            {call}
            print('ran to the end')
        except KeyboardInterrupt as e:
            print('stopped:', e, 'after', round(time.time() - start, 1), 's')
        """, data)
    assert "stopped:" in out, out + err
    assert after < 5, f"took {after:.1f} s to stop"


def test_anneal_returns_the_best_so_far_at_ctrl_c(data):
    out, err, after = interrupted("""
        interp = bounding_table()
        r = wobble.anneal(interp.synthesis_problem(), interp.pose_graph, iterations=100000, batch=2, max_steps=10**12)
        print('interrupted', r.interrupted, 'trials', r.trials, 'best <= initial', r.best_outcome.cost <= r.initial_outcome.cost)
        """, data)
    assert "interrupted True" in out and "best <= initial True" in out, out + err
    assert after < 10


def test_run_trials_stops_at_ctrl_c_and_says_how_many_ran(data):
    # 20000 trials of the bounding table (~4 ms each on two cores: over a minute): SIGINT after
    # 1 s skips the trials not started and raises KeyboardInterrupt counting those that ran
    out, err, after = interrupted("""
        interp = bounding_table()
        graphs = [interp.pose_graph] * 20000
        try:
            wobble.run_trials(interp.synthesis_problem(), graphs)
            print('ran to the end')
        except KeyboardInterrupt as e:
            print('stopped:', e)
        """, data)
    assert "stopped: run_trials stopped by Ctrl-C after" in out and "of 20000 trials" in out, out + err
    assert after < 5
