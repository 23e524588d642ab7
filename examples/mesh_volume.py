#!/usr/bin/python3
"""Mesh a sampled volume (a brain MRI) with the adaptive polygonizer, beside scikit-image's
marching cubes on the same samples.

    PYTHONPATH=build/python /usr/bin/python3 examples/mesh_volume.py [--out DIR] [--factor K]

The volume is `anatomical.nii`, a 33 x 41 x 25 T1-weighted scan at 2 mm that Debian's
python3-nibabel ships among its test data (without nibabel, a synthetic volume: two blobs and
noise). The isosurface is at Otsu's threshold, inside above it. The scan is smoothed first
(a Gaussian of 2 voxels): its noise gives the raw level set details far below a voxel, and the
adaptive method, which resolves what the field holds, spends a minute on them and then says it
cannot (the note of issue 59 has the figures); marching cubes does not look. Both methods get the
same smoothed array: cdp interpolates it with a tricubic B-spline (cdp.volume_field), scikit-image
linearly along cell edges. The script prints both meshes' figures, writes DIR/brain.ply and
DIR/brain_skimage.ply and draws DIR/brain.png (ours, coloured by curvature) with build/bin/render
when that program is built. What it prints also goes to DIR/report.txt.
"""
import argparse
import pathlib
import subprocess
import sys
import time

import numpy as np

import cdp

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCAN = pathlib.Path("/usr/lib/python3/dist-packages/nibabel/tests/data/anatomical.nii")
SMOOTHING_VOXELS = 2.0
# Voxels of background around the scan, so that the interpolant is outside on the grid's faces:
# the scan is cut through the brain, and the spline's coefficients ring next to that jump (with
# three layers and no smoothing, one next to a face was still above the level).
PAD = 5


def load_volume():
    """(array, spacing in mm, name): the scan, or a synthetic stand-in without nibabel."""
    try:
        import nibabel
        image = nibabel.load(SCAN)
        return np.asarray(image.get_fdata()), tuple(float(z) for z in image.header.get_zooms()[:3]), SCAN.name
    except (ImportError, OSError):
        X, Y, Z = np.meshgrid(*[np.linspace(-1, 1, 40)] * 3, indexing="ij")
        blobs = np.exp(-((X - 0.3) ** 2 + Y ** 2 + Z ** 2) / 0.1) + np.exp(-((X + 0.3) ** 2 + Y ** 2 + Z ** 2) / 0.1)
        return blobs + np.random.default_rng(1).normal(0, 0.02, blobs.shape), (1.0, 1.0, 1.0), "two synthetic blobs"


def smallest_angles(V, F):
    """The smallest angle of each triangle, in degrees."""
    P = V[F]
    angles = []
    for i in range(3):
        a, b = P[:, (i + 1) % 3] - P[:, i], P[:, (i + 2) % 3] - P[:, i]
        cos = (a * b).sum(1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return np.min(angles, axis=0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("."), help="output folder (default: .)")
    parser.add_argument("--factor", type=float, default=2, help="the paper's heuristic factor (default 2)")
    parser.add_argument("--smoothing", type=float, default=SMOOTHING_VOXELS,
                        help=f"Gaussian smoothing in voxels before meshing, 0 for none (default {SMOOTHING_VOXELS})")
    parser.add_argument("--level", type=float, help="the isovalue (default: Otsu's threshold of the scan)")
    parser.add_argument("--render", type=pathlib.Path, default=ROOT / "build" / "bin" / "render",
                        help="build/bin/render, for the picture")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    from scipy import ndimage
    from skimage import filters, measure

    report = []

    def say(line):
        print(line)
        report.append(line)

    raw, spacing, name = load_volume()
    level = float(filters.threshold_otsu(raw)) if args.level is None else args.level
    volume = np.pad(raw, PAD, mode="constant", constant_values=raw.min())
    if args.smoothing > 0:
        volume = ndimage.gaussian_filter(volume, args.smoothing)
    origin = tuple(-PAD * s for s in spacing)
    say(f"{name}: {raw.shape} samples at {spacing} mm, level {level:.1f}"
        f"{' (Otsu)' if args.level is None else ''}, smoothed by {args.smoothing} voxels")

    field = cdp.volume_field(volume, spacing=spacing, origin=origin, level=level, inside="above")
    start = time.perf_counter()
    mesh = cdp.polygonize(field, factor=args.factor)
    ours_seconds = time.perf_counter() - start
    summary = mesh.stats["summary"]

    start = time.perf_counter()
    # scikit-image's vertices are in index units times spacing, from the first sample: moved to ours.
    V, F, _, _ = measure.marching_cubes(volume, level=level, spacing=spacing)
    skimage_seconds = time.perf_counter() - start
    V = V + origin
    F = F[:, ::-1]  # its faces turn the other way for a density (inside above the level)
    degenerate = np.isnan(smallest_angles(V, F))

    ours_angles = smallest_angles(mesh.vertices, mesh.faces)
    say(f"ours:         {len(mesh.faces):6d} triangles in {ours_seconds:.3f} s; smallest angle "
          f"{ours_angles.min():.1f} deg, {100 * np.mean(ours_angles < 30):.1f} % under 30; watertight "
          f"{summary['watertight']}, {summary['components']} component(s), genus {summary['genus']}; "
          f"|S - level| at the vertices below {np.abs(field.values(mesh.vertices)).max():.2g}")
    angles = smallest_angles(V, F)[~degenerate]
    residual = np.abs(field.values(V)).max()
    say(f"scikit-image: {len(F):6d} triangles in {skimage_seconds:.3f} s; smallest angle {angles.min():.1f} deg, "
          f"{100 * np.mean(angles < 30):.1f} % under 30, {int(degenerate.sum())} without area; "
          f"|S - level| at the vertices up to {residual:.3g} (linear interpolation of the same samples)")

    cdp.write_mesh(args.out / "brain.ply", mesh.vertices, mesh.faces, mesh.normals,
                   scalars={"mac": cdp.curvature(field, mesh.vertices)["mac"]})
    cdp.write_mesh(args.out / "brain_skimage.ply", V, F)
    (args.out / "report.txt").write_text("\n".join(report) + "\n")
    print(f"wrote {args.out / 'brain.ply'}, {args.out / 'brain_skimage.ply'} and {args.out / 'report.txt'}")
    if not args.render.exists():
        print(f"no picture: {args.render} is not built (cmake --build build --target render)")
        return 0
    picture = args.out / "brain.png"
    subprocess.run([args.render, args.out / "brain.ply", "-o", picture, "--color", "mac", "--wireframe", "--up", "z",
                    "--azimuth", "-60", "--elevation", "20", "--width", "800", "--height", "600"], check=True,
                   stdout=subprocess.DEVNULL)
    print(f"wrote {picture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
