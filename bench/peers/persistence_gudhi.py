# The peer of bench/peers/persistence_gudhi.sh: the same pairs computed by GUDHI (Debian's
# python3-gudhi), an independent library, on the same complex.
#   python3 persistence_gudhi.py VALUES.f32 NLAT NR NLON DIAGRAM.csv
# VALUES.f32 is a dataset's level-0 array (float32, canonical order (lat, r, lon), lon fastest);
# DIAGRAM.csv is `raypc export --what persistence` of the same step. Builds the 1-skeleton of the
# Freudenthal triangulation (edges to the offsets d in {0,1}^3 \ 0, lon wrapping; H0 needs no more)
# as a lower-star filtration in a gudhi.SimplexTree, for f (minimum-saddle pairs) and for -f
# (saddle-maximum pairs), and compares the H0 intervals of positive length with RayPC's pairs.
# The diagram of a function does not depend on how ties are broken, so the values must agree.
# Prints "RESULT <what> <value>" lines and exits 1 on a mismatch.
import csv
import sys
import time

import gudhi
import numpy as np

path, n_lat, n_r, n_lon, diagram = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
f = np.fromfile(path, dtype="<f4").astype(np.float64)
assert f.size == n_lat * n_r * n_lon, (f.size, n_lat, n_r, n_lon)
idx = np.arange(f.size).reshape(n_lat, n_r, n_lon)

edges = []
for d in [(a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1) if (a, b, c) != (0, 0, 0)]:
    src = idx[: n_lat - d[0], : n_r - d[1], :]
    dst = np.roll(idx, -d[2], axis=2)[d[0]:, d[1]:, :]  # lon wraps
    edges.append(np.stack([src.ravel(), dst.ravel()]))
edges = np.concatenate(edges, axis=1)


def h0(values):
    t = time.perf_counter()
    st = gudhi.SimplexTree()
    for v in range(values.size):
        st.insert([v], filtration=values[v])
    for u, v in edges.T:
        st.insert([int(u), int(v)], filtration=max(values[u], values[v]))
    built = time.perf_counter() - t
    t = time.perf_counter()
    st.compute_persistence(persistence_dim_max=False)
    intervals = st.persistence_intervals_in_dimension(0)
    return intervals, built, time.perf_counter() - t


low, built_low, time_low = h0(f)
high, built_high, time_high = h0(-f)
print(f"RESULT gudhi_build_s {built_low + built_high:.2f}")
print(f"RESULT gudhi_persistence_s {time_low + time_high:.3f}")

ours = {"minimum-saddle": [], "saddle-maximum": [], "global": []}
with open(diagram) as file:
    for row in csv.DictReader(file):
        ours[row["kind"]].append((float(row["birth [K]"]), float(row["death [K]"])))


def positive(pairs):
    return sorted((b, d) for b, d in pairs if d - b > 0)


gudhi_min = positive((b, d) for b, d in low if np.isfinite(d))
gudhi_max = positive((-d, -b) for b, d in high if np.isfinite(d))  # superlevel of f = sublevel of -f
essential = [b for b, d in low if not np.isfinite(d)]
ok = True
for name, theirs, mine in (("minimum-saddle", gudhi_min, positive(ours["minimum-saddle"])),
                           ("saddle-maximum", gudhi_max, positive(ours["saddle-maximum"]))):
    # RayPC's CSV has 7 significant digits: compare within 1e-6 of the range.
    tol = 1e-6 * (f.max() - f.min())
    same = len(theirs) == len(mine) and all(abs(a[0] - b[0]) <= tol and abs(a[1] - b[1]) <= tol
                                            for a, b in zip(theirs, mine))
    largest = max((d - b for b, d in mine), default=0)
    print(f"RESULT {name}_pairs raypc={len(mine)} gudhi={len(theirs)} largest={largest:.4g} same={same}")
    ok = ok and same
same_global = len(essential) == 1 and len(ours["global"]) == 1 and abs(essential[0] - ours["global"][0][0]) <= 1e-3
print(f"RESULT essential_class gudhi_birth={essential} raypc_global={ours['global']} same={same_global}")
sys.exit(0 if ok and same_global else 1)
