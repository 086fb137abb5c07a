#!/usr/bin/env python3
"""Independent check of `wobble inspect`: recompute positions (Eq. 4.2) and the mass matrix
M = sum m_k J_k^T J_k (Eq. 4.10) from the JSON's own lattice, modes, lattice coordinates and
masses with the Bernstein basis of Eq. 4.1, in plain Python, and compare."""
import json, math, subprocess, sys

wobble, obj, modes, q_text = sys.argv[1:5]
out = subprocess.run([wobble, "inspect", "--object", obj, "--modes", modes, "--q", q_text,
                      "--qdot", " ".join(["0.1"] * len(q_text.split()))],
                     check=True, capture_output=True, text=True).stdout
d = json.loads(out)
q = [float(v) for v in q_text.split()]
lattice, mode_d = d["lattice"], d["modes"]
n, m, D = len(lattice) - 1, len(lattice[0]) - 1, len(mode_d)
nq = 3 + D
c, s = math.cos(q[2]), math.sin(q[2])

def bern(deg, i, u):
    return math.comb(deg, i) * (1 - u) ** (deg - i) * u ** i

M = [[0.0] * nq for _ in range(nq)]
worst = 0.0
for k, (mass, (u, v)) in enumerate(zip(d["masses"], d["lattice_coords"])):
    l = [0.0, 0.0]
    b = [[0.0, 0.0] for _ in range(D)]
    for i in range(n + 1):
        for j in range(m + 1):
            w = bern(n, i, u) * bern(m, j, v)
            for a in range(2):
                l[a] += w * (lattice[i][j][a] + sum(q[3 + e] * mode_d[e][i][j][a] for e in range(D)))
                for e in range(D):
                    b[e][a] += w * mode_d[e][i][j][a]
    x = [q[0] + c * l[0] - s * l[1], q[1] + s * l[0] + c * l[1]]
    worst = max(worst, math.dist(x, d["x"][k]) / (1 + math.hypot(*x)))
    cols = [[1, 0], [0, 1], [-s * l[0] - c * l[1], c * l[0] - s * l[1]]]
    cols += [[c * be[0] - s * be[1], s * be[0] + c * be[1]] for be in b]
    for r in range(nq):
        for t in range(nq):
            M[r][t] += mass * (cols[r][0] * cols[t][0] + cols[r][1] * cols[t][1])

norm = math.sqrt(sum(v * v for row in M for v in row))
err = math.sqrt(sum((M[r][t] - d["M"][r][t]) ** 2 for r in range(nq) for t in range(nq))) / norm
print(f"positions: worst relative error {worst:.2e}; mass matrix: relative error {err:.2e}")
sys.exit(0 if worst < 1e-12 and err < 1e-12 else 1)
