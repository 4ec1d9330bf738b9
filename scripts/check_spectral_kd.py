#!/usr/bin/env python3
"""An independent check of `polrig spectral kd` on the shipped example spectra.

Planck's law written out again, the CSVs read and interpolated linearly here, and the integrals
taken by the trapezoid rule on a 0.005 nm grid (polrig instead integrates its interpolants
exactly on the union of sample points and samples Planck every 0.1 nm).

    python3 scripts/check_spectral_kd.py [RESPONSE.csv]     (from the repository root)
"""
import bisect
import math
import sys

D = "data/spectra/"


def table(path, col):
    xs, ys, hdr = [], [], None
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        f = line.strip().split(",")
        if hdr is None:
            hdr = f
            continue
        xs.append(float(f[0]))
        ys.append(float(f[hdr.index(col)]))

    def at(x):
        j = bisect.bisect_left(xs, x)
        if xs[j] == x:
            return ys[j]
        t = (x - xs[j - 1]) / (xs[j] - xs[j - 1])
        return ys[j - 1] + t * (ys[j] - ys[j - 1])
    return at


h, c, k = 6.62607015e-34, 299792458.0, 1.380649e-23


def planck(nm, T):
    lam = nm * 1e-9
    return 2 * h * c * c / lam ** 5 / math.expm1(h * c / (lam * k * T))


film = D + "sheet-polarizer-synthetic.csv"
M, m = table(film, "tau_M"), table(film, "tau_m")
R = table(sys.argv[1] if len(sys.argv) > 1 else D + "blue-filter-photodiode-synthetic.csv",
          "response")
etr = table(D + "astm-g173.csv", "extraterrestrial")
direct = table(D + "astm-g173.csv", "direct_am15")


def d_eff(S, lo=320.0, hi=730.0, n=82000):
    num = den = 0.0
    for i in range(n + 1):
        x = lo + (hi - lo) * i / n
        w = 0.5 if i in (0, n) else 1.0
        s = S(x) * R(x)
        num += w * (M(x) - m(x)) * s
        den += w * (M(x) + m(x)) * s
    return num / den


lamp = d_eff(lambda x: planck(x, 2856))
for name, S in (("extraterrestrial", lambda x: etr(x) * (550 / x) ** 4),
                ("direct_am15", lambda x: direct(x) * (550 / x) ** 4),
                ("blackbody 5778 K", lambda x: planck(x, 5778) * (550 / x) ** 4)):
    sky = d_eff(S)
    print(f"sky from {name:17s} kd_lamp {lamp - 1:.8f}  kd_sky {sky - 1:.8f}  "
          f"sky - lamp {sky - lamp:+.8f}")
