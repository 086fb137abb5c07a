#!/usr/bin/env python3
"""Inputs and outputs that are not regular files, bare output names and a full disk, at the CLI.

usage: check_special_files.py WOBBLE DATA_DIR WORK_DIR

- an object, deformation or script file that is a FIFO or a device is refused at once (exit 2,
  named, "not a regular file") instead of waiting forever for a writer or reading without end;
- an output that is a FIFO or a device node is refused (non-zero exit) and left as it was: the
  temporary-file-and-rename writer would otherwise put a regular file in its place (as root,
  `--out /dev/null` replaced the system's /dev/null);
- an output named without a folder is written in the working directory.
(A full disk is tested below the CLI, in pipelines_export_test's FailedWrite: the CLI checks
that an output can be written before a run, which removes a planted temporary file.)
"""
import os
import shutil
import stat
import subprocess
import sys

failures = []


def run(cmd, cwd, timeout=60):
    try:
        p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        failures.append(f"{' '.join(cmd)}: did not return within {timeout} s")
        return None
    return p


def expect(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def main():
    wobble, data, work = sys.argv[1], sys.argv[2], sys.argv[3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    obj, modes = os.path.join(data, "table.obj"), os.path.join(data, "table_modes.def")
    fifo = os.path.join(work, "pipe")
    os.mkfifo(fifo)

    # inputs
    for label, args in [("object FIFO", ["inspect", "--object", fifo, "--modes", modes]),
                        ("modes FIFO", ["inspect", "--object", obj, "--modes", fifo]),
                        ("modes /dev/urandom", ["inspect", "--object", obj, "--modes", "/dev/urandom"]),
                        ("script FIFO", ["run", fifo])]:
        p = run([wobble] + args, work, timeout=20)
        if p is None:
            continue
        expect(p.returncode == 2, f"{label}: exit {p.returncode} (2 expected)")
        expect("not a regular file" in p.stderr, f"{label}: the message says why: {p.stderr.strip()}")
    expect(stat.S_ISFIFO(os.stat(fifo).st_mode), "the FIFO read from is still a FIFO")

    simulate = [wobble, "simulate", "--object", obj, "--modes", modes, "--q", "0 50 0 0 0 0 0", "--duration", "0.05"]
    # outputs that are not regular files
    targets = [("FIFO", fifo, stat.S_ISFIFO)]
    node = os.path.join(work, "null")
    try:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # a /dev/null of our own (root only)
        targets.append(("character device", node, stat.S_ISCHR))
    except PermissionError:
        print("skip the device node: mknod needs root")
    for label, path, is_kind in targets:
        p = run(simulate + ["--out", path], work)
        if p is None:
            continue
        expect(p.returncode != 0, f"--out {label}: exit {p.returncode} (non-zero expected)")
        expect("not a regular file" in p.stderr, f"--out {label}: the message says why: {p.stderr.strip()}")
        expect(is_kind(os.stat(path).st_mode), f"--out {label}: still a {label}, not replaced")

    # a bare output name: the working directory
    p = run(simulate + ["--out", "bare.csv"], work)
    expect(p is not None and p.returncode == 0, "--out bare.csv: exit 0")
    expect(os.path.isfile(os.path.join(work, "bare.csv")), "--out bare.csv: written in the working directory")

    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))
    print("special files: all checks passed")


if __name__ == "__main__":
    main()
