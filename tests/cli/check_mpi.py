#!/usr/bin/env python3
"""Studies and synthesis on MPI ranks (issue 17), at the CLI.

usage: check_mpi.py WOBBLE MPIRUN DATA_DIR WORK_DIR

- the same sweep table, byte for byte, on 1 process with 1 and 2 threads and under
  `mpirun -np 2` and `-np 3`; a case with a bad value is a row, not a dead run;
- `wobble run` of a synthesis script (annealing batches, CMA-ES generations, the saved
  replays) writes the same files on 1 process and under mpirun, and only rank 0 writes;
- a rank killed during a sweep ends the run non-zero with a message naming the rank, and
  the rows finished before are on disk (sweep.csv.partial), equal to the 1-process rows.
CI runs as root: Open MPI's allow-run-as-root variables are set, with --oversubscribe.
"""
import csv
import filecmp
import os
import shutil
import signal
import subprocess
import sys
import time

failures = []


def expect(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


wobble, mpirun, data, work = sys.argv[1:5]
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
here = os.path.dirname(os.path.abspath(__file__))


def mpi(n):
    return [mpirun, "-np", str(n), "--oversubscribe"]


def run(cmd, timeout=600):
    r = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        print(" ".join(cmd), "\n", r.stdout, r.stderr)
    return r


# --- one sweep table everywhere ----------------------------------------------------------
study = [wobble, "sweep", os.path.join(data, "sweep_bounding.wob"), "--param", "seed=1:3:3",
         "--param", "frsin=0.3,-1,0.8", "--param", "iterations=2", "--param", "trial_steps=300",
         "--measure", "cost,trials,distance,state"]
tables = {}
for name, prefix, extra in [("1 thread", [], ["--threads", "1"]), ("2 threads", [], ["--threads", "2"]),
                            ("mpirun -np 2", mpi(2), []), ("mpirun -np 3", mpi(3), [])]:
    out = os.path.join(work, name.replace(" ", "_"))
    r = run(prefix + study + extra + ["--out", out])
    expect(r.returncode == 0, f"sweep on {name}: exit 0 (got {r.returncode})")
    path = os.path.join(out, "sweep.csv")
    expect(os.path.exists(path) and not os.path.exists(path + ".partial"),
           f"sweep on {name}: sweep.csv written, the partial file gone")
    if os.path.exists(path):
        tables[name] = open(path, "rb").read()
    if prefix:
        expect(f"on {prefix[2]} ranks" in r.stdout, f"sweep on {name}: says it ran on {prefix[2]} ranks")
        expect(r.stdout.count("table:") == 1, f"sweep on {name}: only rank 0 prints")
reference = tables.get("1 thread")
rows = list(csv.DictReader(open(os.path.join(work, "1_thread", "sweep.csv")))) if reference else []
expect(len(rows) == 9, f"9 cases, 9 rows (got {len(rows)})")
expect(sum(r["status"] == "ok" for r in rows) == 6 and sum(r["status"] == "bad input" for r in rows) == 3,
       "the 3 cases with frsin -1 are rows with status 'bad input', the other 6 ran")
expect(all(r["cost"] != "" and r["trials"] == "17" for r in rows if r["status"] == "ok"),
       "every case that ran has its cost and 17 trials")
for name, table in tables.items():
    expect(table == reference, f"sweep table on {name} is byte-identical to 1 process, 1 thread")

# --- synthesis of one script on ranks -----------------------------------------------------
script = os.path.join(here, "mpi_synthesis.wob")
outputs = ["anneal.csv", "annealed.wob", "cmaes.csv", "cmaes.wob", "restarts.csv", "restarts.wob"]
single = os.path.join(work, "run_1")
r = run([wobble, "run", script, "--param", f"out={single}"])
expect(r.returncode == 0, "wobble run of the synthesis script: exit 0")
for n in (2, 3):
    ranked = os.path.join(work, f"run_np{n}")
    r = run(mpi(n) + [wobble, "run", script, "--param", f"out={ranked}"])
    expect(r.returncode == 0, f"mpirun -np {n} wobble run: exit 0")
    expect(r.stdout.count("anneal: ") == 2, f"mpirun -np {n} wobble run: rank 0 alone prints")
    for f in outputs:
        a, b = os.path.join(single, f), os.path.join(ranked, f)
        expect(os.path.exists(b) and filecmp.cmp(a, b, shallow=False),
               f"mpirun -np {n}: {f} is the same file as on one process")
    expect(not any(n.endswith(".tmp") for n in os.listdir(ranked)), f"mpirun -np {n}: no temporary file left")

# --- the condition map's rows and a 3D surface fit's starts on ranks ------------------------
import json
maps = {}
fits = {}
curves = {}
for name, prefix in [("1 process", []), ("mpirun -np 2", mpi(2)), ("mpirun -np 3", mpi(3))]:
    out = os.path.join(work, "map_" + name.replace(" ", "_"))
    r = run(prefix + [wobble, "condition", "sweep", "--object", os.path.join(data, "table.obj"), "--step", "30",
                      "--map", "24", "--out", out])
    expect(r.returncode == 0, f"condition sweep --map on {name}: exit 0")
    if os.path.exists(os.path.join(out, "map.csv")):
        maps[name] = open(os.path.join(out, "map.csv"), "rb").read()
    for kind, files, results in [("3D surface fit", ("pot3.obj", "pot3_modes.def3", "pot3_scan.tgt"), fits),
                                 ("2D curve fit", ("table.obj", "table_modes.def", "table_curve.tgt"), curves)]:
        fit = os.path.join(work, kind.replace(" ", "_") + "_" + name.replace(" ", "_") + ".json")
        obj, modes, targets = (os.path.join(data, f) for f in files)
        r = run(prefix + [wobble, "fit", "pose", "--object", obj, "--modes", modes, "--targets", targets, "--out", fit])
        expect(r.returncode == 0, f"{kind} on {name}: exit 0")
        if os.path.exists(fit):
            j = json.load(open(fit))
            results[name] = (j["q"], j["rms_residual"])
expect(len(maps) == 3 and len(set(maps.values())) == 1 and maps["1 process"].count(b"\n") == 24 * 24 + 1,
       "the condition map (24 x 24) is the same file on 1 process and on 2 and 3 ranks")
expect(len(fits) == 3 and all(f == fits["1 process"] for f in fits.values()),
       "the 3D surface fit (its starts solved on the ranks) gives the same q and residual everywhere")
expect(len(curves) == 3 and all(f == curves["1 process"] for f in curves.values()),
       "the 2D curve fit (its starts solved on the ranks) gives the same q and residual everywhere")

# --- a killed rank ----------------------------------------------------------------------
out = os.path.join(work, "killed")
long_study = [wobble, "sweep", os.path.join(data, "sweep_bounding.wob"), "--param", "seed=1:200:200",
              "--param", "iterations=8", "--param", "trial_steps=1200", "--measure", "cost", "--out", out]
ref_out = os.path.join(work, "killed_reference")
r = run(long_study[:-1] + [ref_out, "--threads", "2"])
expect(r.returncode == 0, "the longer study on one process: exit 0")
expect("200 ok" in r.stdout, "every case of the longer study ran (whole seeds from seed=1:200:200)")
reference_rows = {row["case"]: row for row in csv.DictReader(open(os.path.join(ref_out, "sweep.csv")))}
def rows_in(path):
    try:
        return list(csv.DictReader(open(path)))
    except (OSError, csv.Error):
        return []


def rank_pid(rank):
    """The pid of the wobble process of this rank (its environment says its rank)."""
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            environ = open(f"/proc/{pid}/environ", "rb").read().split(b"\0")
            cmdline = open(f"/proc/{pid}/cmdline", "rb").read()
        except OSError:
            continue
        if f"OMPI_COMM_WORLD_RANK={rank}".encode() in environ and b"sweep" in cmdline and b"mpirun" not in cmdline:
            return int(pid)
    return None


def stopped_midway(ranks, out, stop, what):
    """Runs the long study on `ranks` ranks into `out`, calls stop(proc) once 4 rows are on disk,
    and checks what a stopped study must leave: a non-zero exit, rank 0 saying where the rows
    are, and those rows equal to the 1-process run's. Returns mpirun's output."""
    partial = os.path.join(out, "sweep.csv.partial")
    proc = subprocess.Popen(mpi(ranks) + long_study[:-1] + [out], cwd=work, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(rows_in(partial)) < 4 and proc.poll() is None:
        time.sleep(0.05)
    expect(proc.poll() is None and len(rows_in(partial)) >= 4, f"{what}: rows reach disk while the study runs")
    stop(proc)
    try:
        text, _ = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        text, _ = proc.communicate()
        expect(False, f"{what}: mpirun ends within 120 s")
    print(text[-1500:])
    kept = rows_in(partial)
    expect(proc.returncode != 0, f"{what}: the run ends non-zero (got {proc.returncode})")
    expect("finished rows are in " + partial in text, f"{what}: rank 0 says where the finished rows are")
    expect(len(kept) >= 4 and all(row == reference_rows.get(row["case"]) for row in kept),
           f"{what}: the finished rows ({len(kept)}) are on disk and equal the same cases' rows on one process")
    expect(not os.path.exists(os.path.join(out, "sweep.csv")), f"{what}: no complete table is claimed")
    return text


def kill_rank_2(proc):
    victim = rank_pid(2)
    expect(victim is not None, "rank 2's process is found")
    if victim:
        os.kill(victim, signal.SIGKILL)


text = stopped_midway(3, os.path.join(work, "killed"), kill_rank_2, "a killed rank")
expect("rank 2" in text, "a killed rank: mpirun's message names it")
# Ctrl-C: mpirun passes it on as SIGTERM to every rank
stopped_midway(2, os.path.join(work, "ctrl_c"), lambda proc: proc.send_signal(signal.SIGINT), "Ctrl-C")

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all MPI checks passed")
