#!/usr/bin/env python3
"""Designs the band spectra that `ppm export` writes for spectral renderers.

A spectral renderer (pbrt-v4 always, Mitsuba 3's spectral variants) turns each RGB colour
into a smooth spectrum, and a product of smooth spectra is not the product of the RGB
colours: our Cornell box's red wall comes out with a sixth of its blue. Colours that are
constant within three bands of wavelengths multiply band by band as RGB channels do. What
is left is to make each band light exactly one sRGB channel: the light's spectrum inside
band k must give zero in the other two channels. This script finds such a spectrum, as
flat as it can (a flat spectrum keeps the renderers' wavelength sampling quiet), and prints
it as the table `LIGHT` in scenes/src/file/bands.rs.

The bands: blue 360-437.5 and 447.5-497.5 nm, green 497.5-577.5 nm, red 577.5-830 nm and
437.5-447.5 nm. The sRGB blue channel is negative at every wavelength above 514.5 nm, so a
band of long wavelengths alone cannot cancel it: the red band takes a sliver of violet,
where blue is strongly positive. Cell edges lie on half nanometres so that pbrt-v4, which
samples a light's spectrum at the nearest whole nanometre, steps where the colours do.

Usage: python3 scripts/spectral-bands.py  (needs numpy and scipy; reads the CIE 1931
2-degree observer at 1 nm from scenes/tests/data/cie1931.csv)
"""
import pathlib

import numpy as np
from scipy.optimize import lsq_linear

ROOT = pathlib.Path(__file__).resolve().parent.parent
# XYZ to linear sRGB (D65), as both renderers convert.
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]])
EDGES = np.concatenate([[360.0], np.arange(362.5, 830.0, 5.0), [830.0]])
RED, GREEN, BLUE = 0, 1, 2
STEP = 0.1  # nm, the integration step
# Mitsuba 3 develops XYZ over this (1 / MI_CIE_Y_NORMALIZATION), not over the integral of
# its own y-bar (106.857): a flat spectrum of 1 comes out with Y = 1.001 there. pbrt-v4
# divides a light by its own luminance, so only Mitsuba's constant fixes the scale.
MITSUBA_Y_INTEGRAL = 106.75025939941406


def band_of(lo):
    """The band of the cell starting at `lo` nm."""
    if 437.5 <= lo < 447.5 or lo >= 577.5:
        return RED
    if 497.5 <= lo < 577.5:
        return GREEN
    return BLUE


def cell_integrals():
    """Per cell: the integral of each sRGB channel's matching function, as Mitsuba 3
    normalises it."""
    table = np.loadtxt(ROOT / "scenes/tests/data/cie1931.csv", delimiter=",", skiprows=1)
    lam = np.arange(360.0, 830.0, STEP) + STEP / 2
    xyz = np.stack([np.interp(lam, table[:, 0], table[:, i]) for i in (1, 2, 3)], axis=1)
    rgb = xyz @ XYZ_TO_SRGB.T
    y_norm = 1.0 / MITSUBA_Y_INTEGRAL
    cells = np.searchsorted(EDGES, lam, side="right") - 1
    c = np.zeros((len(EDGES) - 1, 3))
    np.add.at(c, cells, rgb * STEP * y_norm)
    return c


def main():
    c = cell_integrals()
    bands = np.array([band_of(lo) for lo in EDGES[:-1]])
    light = np.zeros(len(bands))
    for k in (RED, GREEN, BLUE):
        cells = np.flatnonzero(bands == k)
        others = [j for j in range(3) if j != k]
        # min |w - 1|^2 with w >= 0 and zero response in the other channels (heavily
        # weighted rows stand for the equality constraints).
        a = np.vstack([1e7 * c[cells][:, others].T, np.eye(len(cells))])
        b = np.concatenate([np.zeros(2), np.ones(len(cells))])
        w = lsq_linear(a, b, bounds=(0, np.inf)).x
        w[w < 1e-9] = 0.0
        light[cells] = w / (c[cells, k] @ w)
    response = np.stack([c[bands == k].T @ light[bands == k] for k in range(3)], axis=1)
    print("// rgb response of each band's light (columns R, G, B):")
    for row in response:
        print("//", " ".join(f"{v:+.3e}" for v in row))
    print(f"const LIGHT: [f32; {len(light)}] = [")
    for i in range(0, len(light), 6):
        # The shortest decimals that read back as the same f32.
        print("    " + ", ".join(str(np.float32(v)) for v in light[i:i + 6]) + ",")
    print("];")


if __name__ == "__main__":
    main()
