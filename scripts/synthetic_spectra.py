#!/usr/bin/env python3
"""Writes the synthetic example spectra in data/spectra/ (labelled models, not measurements).

W19 (Wang et al., Sensors 2019) names none of its parts' spectra: "linear-polarizing laminated
films", "a blue filter" shared by the six channels, and a ceramic-package photodiode with a
320-730 nm spectral response and a 1.3 mm x 1.3 mm pixel (these match Hamamatsu's S1087, whose
datasheet gives the same range and a 560 nm peak; W19 does not say so). The shapes below are
smooth models with the qualitative features of those parts; change them, rerun, and the CLI
reads the new files.

    python3 scripts/synthetic_spectra.py data/spectra
"""
import math
import sys
from pathlib import Path


def tau_parallel(nm):
    # iodine-PVA sheet: the pass-axis transmittance falls towards the violet
    return 0.82 - 0.32 * math.exp(-(nm - 320.0) / 70.0)


def tau_crossed(nm):
    # leakage: a floor, a rise into the violet and the red/near-IR rise of iodine-PVA sheets
    return (0.002 + 0.06 * math.exp(-(nm - 380.0) / 30.0)
            + 0.45 / (1.0 + math.exp(-(nm - 705.0) / 18.0)))


def blue_filter(nm, red_leak):
    # a broad blue band-pass (peak 0.85 at 440 nm, FWHM 110 nm) and optionally the near-IR
    # leak of coloured-glass blue filters, which starts near 690 nm
    band = 0.85 * math.exp(-0.5 * ((nm - 440.0) / (110.0 / 2.3548)) ** 2)
    return band + red_leak / (1.0 + math.exp(-(nm - 690.0) / 12.0))


def photodiode(nm):
    # 0 at 320 and 730 nm, 0.3 A/W at the 560 nm peak
    if nm <= 320.0 or nm >= 730.0:
        return 0.0
    if nm <= 560.0:
        return 0.3 * math.sin(math.pi / 2 * (nm - 320.0) / 240.0) ** 2
    return 0.3 * math.cos(math.pi / 2 * (nm - 560.0) / 170.0) ** 2


def g(x):
    return f"{x:.6g}"


def write(path, header, rows):
    with open(path, "w") as f:
        f.write(header)
        for r in rows:
            f.write(",".join(g(v) if isinstance(v, float) else str(v) for v in r) + "\n")


def main(out):
    out = Path(out)
    write(out / "sheet-polarizer-synthetic.csv",
          "# SYNTHETIC sheet-polarizer transmittances (not a measurement, not a datasheet):\n"
          "# a smooth model with the qualitative shape of iodine-PVA sheet polarizers (pass-axis\n"
          "# transmittance falling in the violet; crossed leakage rising in the violet and in the\n"
          "# red). W19 names no film. Written by scripts/synthetic_spectra.py.\n"
          "# tau_M: transmittance for light polarized along the film axis; tau_m: across it.\n"
          "wavelength_nm,tau_M,tau_m\n",
          [(nm, tau_parallel(nm), tau_crossed(nm)) for nm in range(320, 805, 5)])
    for name, leak, what in (("blue-filter-photodiode-synthetic.csv", 0.0, "no red leak"),
                             ("blue-filter-redleak-photodiode-synthetic.csv", 0.05,
                              "a 5 % near-IR leak above 690 nm")):
        write(out / name,
              "# SYNTHETIC responsivity of the shared blue filter times the photodiode (not a\n"
              f"# measurement): filter a Gaussian band-pass, peak 0.85 at 440 nm, FWHM 110 nm, {what};\n"
              "# photodiode 0 at 320 and 730 nm (W19's stated range), 0.3 A/W at 560 nm (the\n"
              "# S1087-class ceramic photodiode W19's description matches; W19 names no model).\n"
              "# Written by scripts/synthetic_spectra.py. response = filter x photodiode, in A/W.\n"
              "wavelength_nm,filter_transmittance,photodiode_A_per_W,response\n",
              [(nm, blue_filter(nm, leak), photodiode(nm), blue_filter(nm, leak) * photodiode(nm))
               for nm in range(320, 735, 5)])


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "data/spectra")
