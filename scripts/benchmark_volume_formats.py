#!/usr/bin/python3
"""Size on disk and write time of a label volume and a CT in every image format Repose writes.

usage: /usr/bin/python3 scripts/benchmark_volume_formats.py LABELS [IMAGE] [--repeat 3] [--work DIR]
       [--formats .nii.gz,.nrrd]
LABELS and IMAGE are any volumes Repose reads (e.g. a `repose pose` run's posed_labels.nii.gz and
posed_image.nii.gz). Each is written through vtkReposeImageWriter as `repose pose` writes it (labels
in the smallest integer type), --repeat times per format; the best time is kept. Prints a Markdown
table: format, MB on disk (header and data files together), seconds, and the read-back check."""
import argparse
import os
import shutil
import sys
import tempfile
import time

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The built Python package, unless PYTHONPATH already names one.
sys.path.append(os.path.join(root, "build", "lib", "python3", "dist-packages"))
from repose import vtkReposeImageReader, vtkReposeImageWriter  # noqa: E402

FORMATS = (".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd", ".vti")


def read(path):
    reader = vtkReposeImageReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetLastError():
        sys.exit(reader.GetLastError())
    return reader.GetOutput()


def write(image, path, labels):
    writer = vtkReposeImageWriter()
    writer.SetFileName(path)
    writer.SetSmallestIntegerType(labels)
    writer.SetInputData(image)
    start = time.perf_counter()
    if not writer.Write():
        sys.exit(writer.GetLastError())
    return time.perf_counter() - start


def voxels(image):
    return vtk_to_numpy(image.GetPointData().GetScalars())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("labels")
    parser.add_argument("image", nargs="?")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--work")
    parser.add_argument("--formats", default=",".join(FORMATS), help="comma-separated extensions")
    args = parser.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-formats-")
    print("| volume | format | MB | write s | read back equal |")
    print("|---|---|---:|---:|---|")
    for kind, path in (("labels", args.labels), ("image", args.image)):
        if not path:
            continue
        image = read(path)
        dims = "x".join(map(str, image.GetDimensions()))
        for ext in args.formats.split(","):
            folder = os.path.join(work, kind + ext.replace(".", "_"))
            seconds = []
            for _ in range(args.repeat):
                shutil.rmtree(folder, ignore_errors=True)
                os.makedirs(folder)
                seconds.append(write(image, os.path.join(folder, kind + ext), kind == "labels"))
            size = sum(os.path.getsize(os.path.join(folder, f)) for f in os.listdir(folder))
            same = ext == ".vti" or np.array_equal(voxels(read(os.path.join(folder, kind + ext))), voxels(image))
            print(f"| {kind} {dims} | {ext} | {size / 1e6:.2f} | {min(seconds):.2f} | {'yes' if same else 'NO'} |")
    if not args.work:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
