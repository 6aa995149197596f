"""The 2026 evaluation's trajectory averages and DTW distances, computed with the reference libraries.

Reads a manifest JSON ({"tests": [{"name": ..., "flights": [CSV, ...]}, ...]}), prepares each flight as
Aerialist reads a log (time and position from the first sample, 0.5 s bin means), averages each test's
flights with tslearn's soft-DTW barycenter (gamma 200), cuts the landing with ruptures' Pelt (rbf, penalty
0.01) and prints, as JSON, every pair's DTW distance (similaritymeasures) and each average's length.
"""

import csv
import json
import sys
import warnings

import numpy as np
import ruptures as rpt
import similaritymeasures
from tslearn.barycenters import softdtw_barycenter

GAMMA = 200.0
PERIOD_US = 500000


def read_flight(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f)]
    t = np.array([float(r["timestamp"]) for r in rows])
    xyz = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    return t - t[0], xyz - xyz[0]


def bin_means(t, xyz):
    # Aerialist's downsample_time: bins (start, start + period], the first also holding its start.
    out = []
    start, i, n = t[0], 0, len(t)
    while i < n:
        j = i
        while j < n and t[j] <= start + PERIOD_US:
            j += 1
        if j > i:
            out.append(xyz[i:j].mean(axis=0))
        i = j
        start += PERIOD_US
    return np.array(out)


def cut_landed(avg):
    bkps = rpt.Pelt(model="rbf").fit(avg).predict(pen=0.01)
    if len(bkps) < 2:
        return avg
    cut = (bkps[-2] + bkps[-1]) // 2
    return np.vstack([avg[:cut], avg[cut:].mean(axis=0)])


def main():
    manifest = json.load(open(sys.argv[1]))
    averages = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for test in manifest["tests"]:
            flights = [bin_means(*read_flight(p)) for p in test["flights"]]
            averages.append(cut_landed(softdtw_barycenter(flights, gamma=GAMMA)))
    pairs = []
    for i in range(len(averages)):
        for j in range(i + 1, len(averages)):
            d, _ = similaritymeasures.dtw(averages[i], averages[j])
            pairs.append([i, j, float(d)])
    json.dump({"lengths": [len(a) for a in averages], "pairs": pairs}, sys.stdout)


if __name__ == "__main__":
    main()
