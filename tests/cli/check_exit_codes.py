#!/usr/bin/env python3
"""One exit-code policy for every subcommand and the interpreter (issue 14), at the CLI.

usage: check_exit_codes.py WOBBLE DATA_DIR WORK_DIR

  2  bad input of any kind, with FILE:LINE when it comes from a file or a script (and the
     script's line when a file the script loads is bad); a request over a limit names the
     limit and how to raise it, and is refused before the work starts;
  3  a numerical stop, whose message names a true cause; every row written is finite and the
     last row is the last finite state;
  1  anything else;
  130 Ctrl-C: the work stops at its next step, keeps what it wrote, and says where it stopped.

The cases are the reproducers of the issue (hangs, overflows, inf energies with exit 0, a
NaN Jacobian's segfault) and one of each class per subcommand.
"""
import csv
import math
import os
import shutil
import signal
import subprocess
import sys
import time

failures = []


def expect(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def run(cmd, cwd, timeout=120):
    try:
        return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        expect(False, f"{' '.join(cmd)}: returned within {timeout} s")
        return None


def case(label, cmd, cwd, code, *needles, timeout=120):
    """Runs cmd; expects exit `code` and every needle in stderr."""
    p = run(cmd, cwd, timeout)
    if p is None:
        return None
    expect(p.returncode == code, f"{label}: exit {p.returncode} ({code} expected)")
    for n in needles:
        expect(n in p.stderr, f"{label}: stderr names {n!r}: {p.stderr.strip()[-300:]}")
    return p


def rows_finite(path):
    """Every value of a CSV is finite; returns the rows (header excluded)."""
    with open(path) as f:
        rows = list(csv.reader(f))[1:]
    bad = [r for r in rows if not all(math.isfinite(float(v)) for v in r)]
    expect(not bad, f"{os.path.basename(path)}: all {len(rows)} rows finite ({len(bad)} not)")
    return rows


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def main():
    wobble, data, work = sys.argv[1], sys.argv[2], sys.argv[3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    obj, modes = os.path.join(data, "table.obj"), os.path.join(data, "table_modes.def")
    body = ["--object", obj, "--modes", modes]
    bad_obj = write(os.path.join(work, "bad.obj"), "lattice 2 2\nbasis bernstein\nsize 100 100\nmass x\n")
    a_file = write(os.path.join(work, "a_file"), "not a folder\n")

    # ---- simulate
    sim = [wobble, "simulate"] + body
    case("simulate: bad object file", [wobble, "simulate", "--object", bad_obj, "--modes", modes], work, 2, "bad.obj:")
    case("simulate: --dt -1", sim + ["--dt", "-1"], work, 2, "--dt")
    case("simulate: 1e11 steps", sim + ["--dt", "1e-9", "--duration", "100"], work, 2, "over the limit", "--max-steps")
    case("simulate: --duration 1e300", sim + ["--duration", "1e300"], work, 2, "over the limit")
    case("simulate: a record over --max-record-mb", sim + ["--duration", "10", "--max-record-mb", "0.01"], work, 2,
         "MiB", "--max-record-mb")
    case("simulate: q-dot 1e160 (infinite kinetic energy)", sim + ["--qdot", "1e160 0 0 0 0 0 0", "--no-ground"], work, 2,
         "energy is not finite")
    case("simulate: --out in a file's place", sim + ["--duration", "0.1", "--out", os.path.join(a_file, "x.csv")], work, 2,
         "--out")
    out = os.path.join(work, "stiff.csv")
    p = case("simulate: ground stiffness 1e306 (an overflowing force)",
             sim + ["--q", "0 50 0 0 0 0 0", "--ground-stiffness", "1e306", "--duration", "5", "--out", out], work, 3)
    if p is not None:
        expect(any(c in p.stderr for c in ("overflowing force", "non-finite energy", "non-finite state")),
               f"simulate: the stop names the cause, not 'singular mass matrix': {p.stderr.strip()}")
        expect("singular mass" not in p.stderr, "simulate: no 'singular mass matrix' for a huge stiffness")
        rows = rows_finite(out)
        expect(len(rows) > 1 and float(rows[-1][0]) < 5.0, "simulate: the rows end at the last finite state")

    # ---- inspect
    case("inspect: q-dot 1e160", [wobble, "inspect"] + body + ["--qdot", "0 0 1e160 0 0 0 0"], work, 2,
         "energy is not finite")
    case("inspect: bad modes file", [wobble, "inspect", "--object", obj, "--modes", bad_obj], work, 2, "bad.obj:")
    small = write(os.path.join(work, "m3.def"), "# a 3x3 mode\nmode small\nx: 1 2 3\n 4 5 6\n 7 8 9\ny: 1 2 3\n 4 5 6\n 7 8 9\n")
    case("inspect: a mode of another lattice size names its file and line",
         [wobble, "inspect", "--object", obj, "--modes", small], work, 2, "m3.def:2:", "3x3 lattice")

    # ---- condition
    case("condition sweep: --step 1e-9 (an int overflow skipped the check)",
         [wobble, "condition", "sweep", "--object", obj, "--step", "1e-9", "--out", work], work, 2, "samples")
    case("condition sweep: --out in a file's place",
         [wobble, "condition", "sweep", "--object", obj, "--out", os.path.join(a_file, "d")], work, 2, "--out")
    case("condition check: bad object", [wobble, "condition", "check", "--object", bad_obj, "--modes", modes], work, 2,
         "bad.obj:")

    # ---- fit
    far = write(os.path.join(work, "far.tgt"), "polyline 0 0 1e160 0 5 5\n")
    case("fit pose: a target at 1e160 (NaN Jacobian, was a segfault)",
         [wobble, "fit", "pose"] + body + ["--targets", far], work, 3, "not finite")
    heavy = write(os.path.join(work, "heavy.tgt"), "point 0 0 100 weight 1e308\npoint 4 300 100\n")
    case("fit pose: weight 1e308", [wobble, "fit", "pose"] + body + ["--targets", heavy], work, 3, "not finite")
    bad_tgt = write(os.path.join(work, "bad.tgt"), "point 0 1 2\npoint zero 1 2\n")
    case("fit pose: bad target file", [wobble, "fit", "pose"] + body + ["--targets", bad_tgt], work, 2, "bad.tgt:2:")

    bad_keys = write(os.path.join(work, "keys.tgt"), "frame 0\npoint 0 0 100\nframe zero\n")
    case("fit trajectory: bad keys file", [wobble, "fit", "trajectory"] + body + ["--reference", bad_keys], work, 2,
         "keys.tgt:3:")
    case("fit trajectory: --every 0", [wobble, "fit", "trajectory"] + body +
         ["--reference", os.path.join(data, "table_keys.tgt"), "--every", "0"], work, 2)
    case("condition time: --dt 0", [wobble, "condition", "time"] + body + ["--dt", "0"], work, 2, "--dt")
    case("condition time: 1e12 steps", [wobble, "condition", "time"] + body + ["--dt", "1e-9", "--duration", "1000"],
         work, 2, "10^7 steps")

    # ---- render, export, view: flags checked before any work
    for sub in ("render", "export"):
        case(f"{sub}: --fps 1e300", [wobble, sub] + body + ["--fps", "1e300", "--out", work], work, 2, "frames")
        case(f"{sub}: 1e11 steps", [wobble, sub] + body + ["--dt", "1e-9", "--duration", "100", "--what", "vtp",
                                                           "--out", work], work, 2, "--max-steps")
        case(f"{sub}: --out in a file's place", [wobble, sub] + body + ["--what", "vtp", "--out", a_file], work, 2, "--out")
    view = [wobble, "view", write(os.path.join(work, "v.wob"), "simull 1\n")]
    if os.environ.get("DISPLAY"):
        case("view: a bad script names its line", view, work, 2, "v.wob:1:")
    else:
        case("view without a display says so", view, work, 2, "X display")

    # ---- run (the interpreter)
    def script(name, text):
        return write(os.path.join(work, name), text)

    start = time.time()
    case("run: set dt 1e15 with a frame record (hung)",
         [wobble, "run", script("dt.wob", "set dt 1e15\nlinear b 2d affine box 1 1 grid 2\nrecord 30\nsimul 1\n")],
         work, 0, timeout=30)
    expect(time.time() - start < 30, "run: set dt 1e15 returns at once")
    case("run: 10^8 steps", [wobble, "run", script("steps.wob", f"load_obj {obj}\nload_def {modes}\nset dt 1e-7\nsimul 10\n")],
         work, 2, "steps.wob:4:", "max_steps")
    case("run: 10^8 steps allowed, their record is not",
         [wobble, "run", script("record.wob", f"load_obj {obj}\nload_def {modes}\nset dt 1e-7\nset max_steps 1e9\nsimul 10\n")],
         work, 2, "record.wob:5:", "max_record_mb")
    case("run: --max-steps from the command line",
         [wobble, "run", "--max-steps", "10", script("flag.wob", f"load_obj {obj}\nsimul 1\n")], work, 2, "flag.wob:2:",
         "over the limit of 10")
    case("run: a bad file the script loads", [wobble, "run", script("load.wob", f"# one\nload_obj {bad_obj}\n")], work, 2,
         "load.wob:2:", "bad.obj:")
    case("run: threads 100000", [wobble, "run", script("threads.wob", "set threads 100000\n")], work, 2, "threads.wob:1:")
    case("run: grid 1000 in 3D", [wobble, "run", script("grid.wob", "linear b 3d affine box 1 1 1 grid 1000\n")], work, 2,
         "grid.wob:1:", "mass points")
    # keys from 0 to 1e300 in 0.5 s ask for an infinite speed at once: bad input, said so
    case("run: key 0.5 bend=1e300",
         [wobble, "run", script("key.wob", f"load_obj {obj}\nload_def {modes}\nkey 0 bend=0\nkey 0.5 bend=1e300\nkeyframe\n")],
         work, 2, "key.wob:5:", "energy is not finite")
    csv_out = os.path.join(work, "fr.csv")
    # a table sliding on the ground at 30/s: friction damping 1e300 moves its anchors past any
    # finite ground energy (the issue's `set frconst 1e300` wrote inf with exit 0)
    p = case("run: set frconst 1e300 on a sliding table",
             [wobble, "run", script("fr.wob", f"load_obj {obj}\nload_def {modes}\nset frconst 1e300\n"
                                              f"set_vec q 0 0 0 0 0 0 0\nset_vec dq 30 -5 0 0 0 0 0\noutput {csv_out}\n"
                                              f"simul 1\n")], work, 3, "fr.wob:7:", "non-finite energy")
    if p is not None and os.path.exists(csv_out):
        rows_finite(csv_out)

    # ---- output files a script cannot write at all (a folder where a file is): bad input, exit 2
    blocker = write(os.path.join(work, "a_file"), "x")
    for line, needle in ((f"output {blocker}/x.csv", "output:"), (f"save {blocker}/x.wob", "save:"),
                         (f"set anneal_csv {blocker}/h.csv", "anneal_csv:")):
        case(f"run: {line.split()[0]} under a regular file",
             [wobble, "run", script("unwritable.wob", f"load_obj {obj}\nload_def {modes}\n{line}\n")], work, 2,
             "unwritable.wob:3:", needle)
    # a folder's name where a file's is expected (trailing '/', '.'): refused when the line is
    # read, not at the write (was exit 1 "is a directory" after the run; fuzz_script finding)
    for line in (f"output {work}/new_folder/", f"save {work}/.", f"set anneal_csv {work}/"):
        case(f"run: {line.split()[0]} naming a folder",
             [wobble, "run", script("folder_out.wob", f"load_obj {obj}\nload_def {modes}\n{line}\nsimul 1\n")], work, 2,
             "folder_out.wob:3:", "names a folder")

    # ---- one policy for every command (issue 50): an output it cannot write is bad input (exit 2,
    # naming the flag) before any work; a FIFO at an output or its temporary or partial file is
    # refused, never opened (opening one for writing blocks until a reader comes)
    case("condition check: --json under a regular file",
         [wobble, "condition", "check"] + body + ["--json", os.path.join(a_file, "r.json")], work, 2, "--json:")
    case("mesh --make: --out under a regular file",
         [wobble, "mesh", "--make", "table", "--out", os.path.join(a_file, "t.vtp")], work, 2, "--out:")
    fifos = os.path.join(work, "fifos")
    os.makedirs(fifos)
    os.mkfifo(os.path.join(fifos, "x.csv.tmp"))
    case("simulate: a FIFO at the temporary file", sim + ["--duration", "0.1", "--out", os.path.join(fifos, "x.csv")], work,
         2, "--out:", "is a FIFO", timeout=30)
    os.mkfifo(os.path.join(fifos, "sweep.csv.partial"))
    case("sweep: a FIFO at sweep.csv.partial",
         [wobble, "sweep", os.path.join(data, "sweep_bounding.wob"), "--param", "seed=1:2:2", "--out", fifos], work, 2,
         "sweep.csv.partial", "is a FIFO", timeout=30)
    # a true cause: a duration under half a step leaves no step (was "--knots must be from 2 to 1")
    case("fit spacetime: --duration shorter than half a step",
         [wobble, "fit", "spacetime"] + body + ["--duration", "0.001", "--dt", "0.01", "--upright"], work, 2,
         "--duration 0.001 is shorter than half a step")
    # a subnormal number is a finite number: accepted like any other (was refused as not finite)
    case("simulate: a subnormal mode amplitude (1e-310)", sim + ["--q", "0 50 0 1e-310 0 0 0", "--duration", "0.1"], work, 0)
    case("inspect: the smallest subnormal (4.9e-324) in --q", [wobble, "inspect"] + body + ["--q", "0 50 0 4.9e-324 0 0 0"],
         work, 0)
    # standard input that is no script: refused at its first line, not read whole into memory
    for label, source in (("/dev/zero", "/dev/zero"), ("a 1 MB comment line", write(os.path.join(work, "long_line.txt"), "#" + "x" * 1000000))):
        with open(source, "rb") as stdin:
            try:
                p = subprocess.run([wobble, "run"], cwd=work, stdin=stdin, capture_output=True, text=True, timeout=30)
                expect(p.returncode == 2 and "<stdin>:1:" in p.stderr,
                       f"run < {label}: exit {p.returncode} (2 expected) naming <stdin>:1: {p.stderr.strip()[-200:]}")
            except subprocess.TimeoutExpired:
                expect(False, f"run < {label}: returned within 30 s")

    # ---- a full disk (a 400 kB tmpfs, when this machine lets us mount one): exit 1 with the
    # system's text, and the files of the earlier run unchanged (was: exit 0, empty EXRs). A
    # displacement EXR is 176 kB and two are written at once (one writer thread per core): the
    # disk holds two, so the first always completes whatever the threads' timing (at 200 kB, two
    # in flight could both fail, leaving nothing to compare), and the 61 files still fill it
    full = os.path.join(work, "full")
    os.makedirs(full)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", full], capture_output=True).returncode == 0
    if not mounted:
        print("skip a full disk: cannot mount a tmpfs here")
    else:
        try:
            # the same export twice: a file the second one replaces is byte for byte the first's,
            # so any change is a truncated or emptied file
            export = [wobble, "export"] + body + ["--q", "0 50 0 0 0 0 0", "--duration", "2", "--what", "disp",
                                                  "--out", full]
            case("export on a disk that fills up", export, work, 1, "No space left on device")
            kept = {}
            for root, _, files in os.walk(full):
                for f in files:
                    with open(os.path.join(root, f), "rb") as h:
                        kept[os.path.join(root, f)] = h.read()
            expect(kept and all(len(v) > 0 for v in kept.values()), f"full disk: {len(kept)} files written, none empty")
            case("export again on the full disk", export, work, 1, "No space left on device")
            same = all(open(k, "rb").read() == v for k, v in kept.items())
            expect(same, "full disk: every file of the first export is unchanged")
            left = [f for _, _, files in os.walk(full) for f in files if f.endswith(".tmp")]
            expect(not left, f"full disk: no temporary file left ({left[:3]})")
            # a script's own writes: the disk failing is exit 1 (not bad input), naming the line;
            # first the disk is filled to its last byte
            with open(os.path.join(full, "filler"), "wb", buffering=0) as f:
                for size in (65536, 4096, 1):
                    try:
                        while f.write(b"\0" * size):
                            pass
                    except OSError:
                        continue
            out_csv = os.path.join(full, "run.csv")
            case("run: output onto the full disk",
                 [wobble, "run", script("full_out.wob", f"load_obj {obj}\nload_def {modes}\nset_vec q 0 50 0 0 0 0 0\n"
                                                        f"output {out_csv}\nsimul 5\n")],
                 work, 1, "full_out.wob:5:", "output:", "No space left on device")
            case("run: save onto the full disk",
                 [wobble, "run", script("full_save.wob", f"load_obj {obj}\nload_def {modes}\n"
                                                         f"save {os.path.join(full, 'replay.wob')}\n")],
                 work, 1, "full_save.wob:3:", "save:", "No space left on device")
        finally:
            subprocess.run(["umount", full])

    # ---- Ctrl-C: stops at the next step, keeps the rows, says where, exit 130
    out = os.path.join(work, "long.csv")
    proc = subprocess.Popen(sim + ["--q", "0 50 0 0 0 0 0", "--duration", "1e5", "--dt", "0.005", "--every", "100",
                                   "--out", out], cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
        expect(proc.returncode == 130, f"simulate + Ctrl-C: exit {proc.returncode} (130 expected)")
        expect("stopped by Ctrl-C at t =" in err and out in err, f"simulate + Ctrl-C: says where: {err.strip()}")
        expect(os.path.exists(out) and len(rows_finite(out)) > 1, "simulate + Ctrl-C: the rows so far are written")
    except subprocess.TimeoutExpired:
        proc.kill()
        expect(False, "simulate + Ctrl-C: stopped within 30 s")

    # Ctrl-C in an optimiser: anneal and cmaes stop between batches, adopt the best so far, 130
    setup = []
    with open(os.path.join(data, "bounding_table.wob")) as f:
        for line in f:
            if line.startswith("anneal"):
                break
            if line.startswith(("load_obj", "load_def")):
                line = line.split()[0] + " " + os.path.join(data, line.split()[1]) + "\n"
            if not line.startswith("set anneal_csv"):
                setup.append(line)
    for command, round_name in (("anneal", "iteration"), ("cmaes", "generation")):
        long_run = script(f"long_{command}.wob", "".join(setup) + f"set max_steps 1e15\n{command} 1000000\n")
        proc = subprocess.Popen([wobble, "run", long_run], cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(1.5)
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=60)
            if "built without pagmo2" in err:
                print(f"skip {command} + Ctrl-C: built without pagmo2")
                continue
            expect(proc.returncode == 130, f"{command} + Ctrl-C: exit {proc.returncode} (130 expected)")
            expect(f"{command} stopped by Ctrl-C after {round_name}" in err and "best pose graph so far" in err,
                   f"{command} + Ctrl-C: says how far it got: {err.strip()[-300:]}")
        except subprocess.TimeoutExpired:
            proc.kill()
            expect(False, f"{command} + Ctrl-C: stopped within 60 s")

    if failures:
        print(f"{len(failures)} failure(s)")
        sys.exit(1)
    print("all exit codes as the policy says")


if __name__ == "__main__":
    main()
