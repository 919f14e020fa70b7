#!/usr/bin/env python3
"""Reference ADEV, MDEV, HDEV and TDEV from allantools for tests/host_sim/test_deviations.cpp.

Run outside the repository with allantools on the path, e.g.
    cd /tmp && PYTHONPATH=/path/to/allantools /usr/bin/python3 make_golden.py OUTDIR
(ALLANTOOLS_COMMIT=<hash> names the allantools commit when its folder is not a git checkout.)
It writes OUTDIR/dev_input.csv (the input, t [s] and y, 3072 samples at 100 Hz, integer counts
times an LSB of 1e-6), OUTDIR/dev_input_float.csv (float values on no grid: an accelerometer's
gravity offset, the same counts scaled by an irrational step, plus a uniform fraction) and
OUTDIR/allantools_dev.csv (the reference values). Not part of the
build or of CI: the two files are committed next to this script.

Deviations, all with data_type="freq", rate=100:
  adev: allantools.oadev (fully overlapping Allan deviation, NIST SP 1065 eqn. 11)
  mdev: allantools.mdev (modified Allan deviation, NIST SP 1065 eqn. 14)
  hdev: allantools.ohdev (overlapping Hadamard deviation, NIST SP 1065 eqn. 20)
  tdev: allantools.tdev (time deviation, tau mdev / sqrt(3), NIST SP 1065 eqn. 15)
EDF: allantools.ci.edf_greenhall (Greenhall & Riley 2003), white FM (alpha = 0), fully
overlapping; modified for mdev and tdev. Interval: allantools.ci.confidence_interval at 0.683.
Grids: "octave" and "decade" on the 3072 samples, "all" on the first 60 (every averaging
factor up to each deviation's last one); the float values on "octave" (label float_octave).
"""
import os
import subprocess
import sys

import numpy as np
import allantools
from allantools import ci

N_SAMPLES = 3072
N_PREFIX = 60
RATE_HZ = 100.0
LSB = 1e-6
CONFIDENCE = 0.683


def counts():
    """Integer counts: offset + slow drift + uniform white noise + a +-3 random walk.

    A 64-bit linear congruential generator (Knuth's MMIX constants), top bits used, so any
    implementation can regenerate the same sequence."""
    state = 12345
    out = []
    walk = 0
    for k in range(N_SAMPLES):
        state = (6364136223846793005 * state + 1442695040888963407) % (1 << 64)
        white = (state >> 33) % 401 - 200
        state = (6364136223846793005 * state + 1442695040888963407) % (1 << 64)
        walk += (state >> 33) % 7 - 3
        out.append(1000 + k // 64 + white + walk)
    return out


def float_values(c):
    """Values no LSB grid holds: 9.80665 + (count - 1000) x 1e-6 / sqrt(2) + u x 3e-7, u in [0, 1)
    from the same generator with another seed."""
    state = 987654321
    out = []
    for k in c:
        state = (6364136223846793005 * state + 1442695040888963407) % (1 << 64)
        u = (state >> 11) / float(1 << 53)
        out.append(9.80665 + (k - 1000) * 1e-6 / 2.0 ** 0.5 + u * 3e-7)
    return out


def write_input(path, values):
    with open(path, "w") as f:
        f.write("t,y\n")
        for k, v in enumerate(values):
            f.write("%r,%s\n" % (k / RATE_HZ, v))


def rows(y, grid, label):
    n_phase = len(y) + 1
    out = []
    runs = [
        ("adev", allantools.oadev, 2, False),
        ("mdev", allantools.mdev, 2, True),
        ("hdev", allantools.ohdev, 3, False),
        ("tdev", allantools.tdev, 2, True),
    ]
    for kind, fn, d, modified in runs:
        taus, devs, _, ns = fn(y, rate=RATE_HZ, data_type="freq", taus=grid)
        for tau, dev, n in zip(taus, devs, ns):
            m = int(round(tau * RATE_HZ))
            edf = ci.edf_greenhall(alpha=0, d=d, m=m, N=n_phase, overlapping=True,
                                   modified=modified)
            lo, hi = ci.confidence_interval(dev, edf, ci=CONFIDENCE)
            out.append("%s,%s,%d,%r,%r,%d,%r,%r,%r" % (label, kind, m, float(tau), float(dev),
                                                      int(n), float(edf), float(lo), float(hi)))
    return out


def main():
    outdir = sys.argv[1] if len(sys.argv) > 1 else "."
    c = counts()
    values = [repr(v * LSB) for v in c]
    write_input(os.path.join(outdir, "dev_input.csv"), values)
    y = np.array([float(v) for v in values])
    fvalues = [repr(v) for v in float_values(c)]
    write_input(os.path.join(outdir, "dev_input_float.csv"), fvalues)
    yf = np.array([float(v) for v in fvalues])
    commit = os.environ.get("ALLANTOOLS_COMMIT", "unknown")
    try:
        commit = subprocess.check_output(
            ["git", "-C", os.path.dirname(allantools.__file__), "rev-parse", "HEAD"],
            stderr=subprocess.DEVNULL).decode().strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    lines = [
        "# allantools %s (commit %s), numpy %s: oadev/mdev/ohdev/tdev, data_type=freq, rate=100"
        % (allantools.__version__, commit, np.__version__),
        "# made by: cd /tmp && PYTHONPATH=<allantools> python3 make_golden.py OUTDIR"
        " (tests/host_sim/deviations/make_golden.py)",
        "# edf: ci.edf_greenhall(alpha=0, overlapping=True), ci_lo/ci_hi at 0.683;"
        " grid all60: the first 60 samples",
        "grid,kind,af,tau_s,dev,n,edf,ci_lo,ci_hi",
    ]
    lines += rows(y, "octave", "octave")
    lines += rows(y, "decade", "decade")
    lines += rows(y[:N_PREFIX], "all", "all60")
    lines += rows(yf, "octave", "float_octave")
    with open(os.path.join(outdir, "allantools_dev.csv"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
