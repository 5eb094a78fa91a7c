"""Renders the Mitsuba 3 fixtures of tests/tests/against_mitsuba.rs.

Each scene file tests/fixtures/mitsuba/NAME.toml is exported with `ppm export --format
mitsuba` and rendered by Mitsuba 3's path tracer (`scalar_rgb`) in BATCHES independent
batches, each with its own seed. The mean of the batches is written as NAME.exr, the
variance of that mean per pixel and channel (the spread of the batch means over BATCHES)
as NAME.var.exr, as `ppm reference` writes them, and what was done as NAME.json.

Needs: Python 3.11 or later with mitsuba==3.9.1 and numpy, and the `ppm` binary
(scripts/mitsuba/fixtures.sh builds it and runs this). Run it through fixtures.sh; its
header says how long it takes.

    python3 fixtures.py --ppm PATH/TO/ppm [--threads 2] [--only NAME ...] [--spp N]

`--meshes` (re)writes the shared inputs of the scenes first: sphere.obj, the sphere every
scene holds, and checker.png, the textured scene's image. Both are written the same, byte
for byte, on every run; the scene files are written by hand.

`--coat` prints, for each coated fixture, the internal reflectance of the coat that Mitsuba's
`plastic` or `roughplastic` uses (implied by its diffuse component's value at two albedos
with `nonlinear` on), which the test's allowance for the rough coat quotes; it renders
nothing.
"""

import argparse
import json
import math
import struct
import subprocess
import tempfile
import time
import tomllib
import zlib
from pathlib import Path

FIXTURES = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "mitsuba"

# Every fixture's image size, which the test renders at too.
SIZE = 32

# Independent batches per fixture: the variance of the mean comes from their spread, so it is
# itself an estimate with BATCHES - 1 degrees of freedom per pixel (the test sums it over
# blocks of pixels, where it settles).
BATCHES = 16

# Samples per pixel, all batches together: Mitsuba's variance is then a sixteenth of our path
# tracer's in the test (2,048 or 4,096 spp) or less, so the comparison's noise is mostly ours,
# which the test can afford to lower.
SPP = 65536

# The fixtures, in the order they are rendered: one scene file NAME.toml each.
NAMES = [
    "diffuse",
    "textured",
    "mirror",
    "glass",
    "rough-glass",
    "conductor",
    "rough-conductor",
    "anisotropic-conductor",
    "coated",
    "rough-coated",
]


def sphere_obj(lon=24, lat=12):
    """A unit sphere of `lon` x `lat` facets, wound outwards, with texture coordinates: `u`
    the longitude (so an anisotropic lobe's tangent runs around the sphere), `v` from 0 at
    the south pole to 1 at the north. Each pole is one vertex with a texture coordinate per
    facet around it; the seam repeats its column of coordinates."""
    lines = [f"# unit UV sphere, {lon} x {lat} facets: scripts/mitsuba/fixtures.py --meshes"]
    index = {}

    def vertex(i, j):
        # Ring i from the north pole (0) to the south (lat); the poles are one vertex each.
        key = (i, 0 if i in (0, lat) else j % lon)
        if key not in index:
            theta, phi = math.pi * i / lat, 2.0 * math.pi * key[1] / lon
            p = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            lines.append("v " + " ".join(f"{c + 0.0:.5f}" for c in p))
            index[key] = len(index) + 1
        return index[key]

    texcoords = {}

    def texcoord(u, v):
        if (u, v) not in texcoords:
            lines.append(f"vt {u:.5f} {v:.5f}")
            texcoords[(u, v)] = len(texcoords) + 1
        return texcoords[(u, v)]

    faces = []
    for i in range(lat):
        for j in range(lon):
            # The quad between rings i and i + 1, columns j and j + 1, counter-clockwise seen
            # from outside (phi grows towards -z, so that u grows to the right of a viewer
            # at -z looking at the sphere).
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            uv = lambda c: ((c[1] if c[0] not in (0, lat) else j + 0.5) / lon, 1.0 - c[0] / lat)
            refs = [(vertex(*c), texcoord(*uv(c))) for c in corners]
            if i == 0:
                faces.append([refs[0], refs[1], refs[2]])
            elif i == lat - 1:
                faces.append([refs[0], refs[1], refs[3]])
            else:
                faces.append([refs[0], refs[1], refs[2]])
                faces.append([refs[0], refs[2], refs[3]])
    for face in faces:
        lines.append("f " + " ".join(f"{v}/{t}" for v, t in face))
    return "\n".join(lines) + "\n"


def check_outward(text):
    """Every facet of the OBJ `text` turns its normal away from the centre."""
    vs = [tuple(map(float, l.split()[1:])) for l in text.splitlines() if l.startswith("v ")]
    for l in text.splitlines():
        if l.startswith("f "):
            a, b, c = (vs[int(r.split("/")[0]) - 1] for r in l.split()[1:])
            e1 = [b[k] - a[k] for k in range(3)]
            e2 = [c[k] - a[k] for k in range(3)]
            i, j = (1, 2, 0), (2, 0, 1)
            n = [e1[i[k]] * e2[j[k]] - e1[j[k]] * e2[i[k]] for k in range(3)]
            centre = [(a[k] + b[k] + c[k]) / 3 for k in range(3)]
            assert sum(n[k] * centre[k] for k in range(3)) > 0, f"inward facet: {l}"


def checker_png(columns=8, rows=4, cell=4, dark=(40, 90, 160), light=(235, 225, 200)):
    """An 8-bit sRGB PNG of a checkerboard of two colours, `columns` x `rows` squares of
    `cell` x `cell` texels each (so that a bilinear lookup blurs only their edges)."""
    raw = b""
    for y in range(rows * cell):
        row = (dark if (x // cell + y // cell) % 2 else light for x in range(columns * cell))
        raw += b"\0" + b"".join(bytes(c) for c in row)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", columns * cell, rows * cell, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def write_meshes():
    obj = sphere_obj()
    check_outward(obj)
    (FIXTURES / "sphere.obj").write_text(obj)
    (FIXTURES / "checker.png").write_bytes(checker_png())


def coat_internal_reflectance(ior, alpha):
    """The internal reflectance `F` of Mitsuba's coat of index `ior` and GGX roughness `alpha`
    (`plastic` when 0): with `nonlinear` on, its diffuse part is `albedo t_i t_o / (pi ior^2
    (1 - albedo F))`, so the ratio of its values at two albedos gives `F`."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("scalar_rgb")

    def diffuse(albedo):
        bsdf = {"type": "plastic"}
        if alpha > 0:
            bsdf = {"type": "roughplastic", "distribution": "ggx", "alpha": alpha}
        bsdf.update({"int_ior": ior, "ext_ior": 1.0, "nonlinear": True,
                     "diffuse_reflectance": {"type": "rgb", "value": [albedo] * 3}})
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi, si.sh_frame = mi.Vector3f(0, 0, 1), mi.Frame3f(mi.Vector3f(0, 0, 1))
        ctx = mi.BSDFContext()
        # The diffuse part alone; the coat's lobe is nil this far from the mirror direction.
        ctx.component = 1
        wo = mi.Vector3f(-math.sqrt(0.75), 0, 0.5)
        return mi.load_dict(bsdf).eval(ctx, si, wo)[0] / albedo

    a, b = 0.7, 0.35
    r = diffuse(a) / diffuse(b)  # (1 - b F) / (1 - a F)
    return (r - 1) / (r * a - b)


def print_coats():
    for path in sorted(FIXTURES.glob("*.toml")):
        sample = tomllib.loads(path.read_text())["materials"]["sample"]
        if sample["type"] == "coated":
            ior, alpha = sample.get("ior", 1.5), sample.get("alpha", 0.0)
            f = coat_internal_reflectance(ior, alpha)
            print(f"{path.stem}: Mitsuba's internal reflectance {f:.4f} (ior {ior}, alpha {alpha})")


def render(ppm, name, spp, threads):
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    mi.set_variant("scalar_rgb")
    dr.set_thread_count(threads)
    per_batch = spp // BATCHES
    with tempfile.TemporaryDirectory() as out:
        subprocess.run(
            [ppm, "export", str(FIXTURES / f"{name}.toml"), "--format", "mitsuba",
             "--width", str(SIZE), "--height", str(SIZE), "--spp", str(per_batch), "-o", out],
            check=True, stdout=subprocess.DEVNULL,
        )
        # One scene file, named by the scene's `name` (made safe for a file name).
        (xml,) = Path(out).glob("*.xml")
        scene = mi.load_file(str(xml))
        start = time.time()
        batches = np.stack([
            np.array(mi.render(scene, spp=per_batch, seed=seed), dtype=np.float64)[:, :, :3]
            for seed in range(BATCHES)
        ])
        seconds = time.time() - start
    mean = batches.mean(axis=0)
    # The variance of the mean of BATCHES independent estimates.
    variance = batches.var(axis=0, ddof=1) / BATCHES
    for image, path in [(mean, f"{name}.exr"), (variance, f"{name}.var.exr")]:
        mi.Bitmap(image.astype(np.float32), mi.Bitmap.PixelFormat.RGB).write(str(FIXTURES / path))
    noise = math.sqrt(variance.mean()) / mean.mean()
    summary = {
        "renderer": f"Mitsuba {mi.__version__} scalar_rgb, "
                    "path tracer (unbounded depth), box filter",
        "scene": f"{name}.toml",
        "width": SIZE,
        "height": SIZE,
        "spp": per_batch * BATCHES,
        "batches": BATCHES,
        "seeds": f"0-{BATCHES - 1}",
        "threads": threads,
        "seconds": round(seconds, 1),
        "relative_noise": round(noise, 6),
        "mean": [round(float(c), 6) for c in mean.mean(axis=(0, 1))],
    }
    (FIXTURES / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
    spp = per_batch * BATCHES
    print(f"{name}: {spp} spp in {seconds:.1f} s, relative noise {noise:.5f}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ppm", help="the ppm binary, for `ppm export` (needed unless --coat)")
    parser.add_argument("--threads", type=int, default=2, help="Mitsuba's render threads")
    parser.add_argument("--only", nargs="*", help="fixtures to render (default: all)")
    parser.add_argument("--spp", type=int, help="samples per pixel for every fixture (a trial)")
    parser.add_argument("--meshes", action="store_true",
                        help="rewrite sphere.obj and checker.png first")
    parser.add_argument("--coat", action="store_true",
                        help="print Mitsuba's coats' internal reflectance; render nothing")
    args = parser.parse_args()
    if args.coat:
        print_coats()
        return
    if not args.ppm:
        parser.error("--ppm is needed to export the scenes")
    if args.meshes:
        write_meshes()
    for name in args.only or NAMES:
        render(args.ppm, name, args.spp or SPP, args.threads)


if __name__ == "__main__":
    main()
