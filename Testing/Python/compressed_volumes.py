"""NRRD and MetaImage outputs are compressed as .nii.gz is (NRRD gzip encoding, MetaImage zlib;
a detached .nhdr keeps raw data), hold the same voxels as posed_labels.nii.gz (read by Repose's
reader and, independently, by Python's gzip and zlib), and a damaged one (gzip cut short, a flipped
byte, a .zraw cut short) is refused on read with one line naming the file."""
import gzip
import os
import shutil
import sys
import zlib

import numpy as np

from repose_testing import TEMP, TESTING, TINY, Image, check, expect_refusal, read_mha, run

failures = []
work = os.path.join(TEMP, "compressed_volumes")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/damaged")
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
for fmt in ("nii.gz", "nrrd", "mha", "mhd", "nhdr"):
    run("pose", "--case", f"{TINY}/case", "--pose", pose, "--format", fmt, "--out", f"{work}/{fmt}")
reference = Image(f"{work}/nii.gz/posed_labels.nii.gz")
raw_bytes = reference.a.size  # the tiny phantom's labels are unsigned char


def nrrd_parts(path):
    data = open(path, "rb").read()
    head, _, body = data.partition(b"\n\n")
    fields = dict(l.split(": ", 1) for l in head.decode().splitlines()[1:] if ": " in l and not l.startswith("#"))
    return fields, body


fields, body = nrrd_parts(f"{work}/nrrd/posed_labels.nrrd")
voxels = np.frombuffer(gzip.decompress(body), np.uint8).reshape(reference.a.shape)
size = os.path.getsize(f"{work}/nrrd/posed_labels.nrrd")
check(fields.get("encoding") == "gzip" and np.array_equal(voxels, reference.a) and size * 10 < raw_bytes,
      f"posed_labels.nrrd is gzip-encoded: {size} B for {raw_bytes} B of voxels, the voxels of the .nii.gz", failures)
mha, header = read_mha(f"{work}/mha/posed_labels.mha")
size = os.path.getsize(f"{work}/mha/posed_labels.mha")
check(header.get("CompressedData") == "True" and np.array_equal(mha[..., 0], reference.a) and size * 10 < raw_bytes,
      f"posed_labels.mha is zlib-compressed: {size} B, the voxels of the .nii.gz", failures)
mhd = dict(l.split(" = ", 1) for l in open(f"{work}/mhd/posed_labels.mhd").read().splitlines())
zraw = f"{work}/mhd/{mhd['ElementDataFile']}"
check(mhd.get("CompressedData") == "True" and zraw.endswith(".zraw")
      and np.array_equal(np.frombuffer(zlib.decompress(open(zraw, "rb").read()), np.uint8), reference.a.ravel()),
      f"posed_labels.mhd names its zlib data {os.path.basename(zraw)}, the voxels of the .nii.gz", failures)
fields, body = nrrd_parts(f"{work}/nhdr/posed_labels.nhdr")
check(fields.get("encoding") == "raw" and os.path.getsize(f"{work}/nhdr/{fields['data file']}") == raw_bytes,
      "a detached .nhdr keeps its data raw", failures)
for fmt in ("nrrd", "mha", "mhd", "nhdr"):
    name = f"{work}/{fmt}/posed_labels.{fmt}"
    check(np.array_equal(Image(name).a, reference.a), f"Repose reads back posed_labels.{fmt} as written", failures)
leftovers = [f for fmt in os.listdir(work) for f in os.listdir(f"{work}/{fmt}") if f.startswith(".repose-tmp")]
check(not leftovers, "no temporary files left beside the outputs", failures)

# The written files damaged: each refused with one line, by the reader and by the CLI.
nrrd = open(f"{work}/nrrd/posed_labels.nrrd", "rb").read()
mha = open(f"{work}/mha/posed_labels.mha", "rb").read()
data_start = mha.index(b"ElementDataFile = LOCAL\n") + len("ElementDataFile = LOCAL\n")


def flipped_at(at):
    f = bytearray(mha)
    f[at] ^= 0x55
    return bytes(f)


def damages(candidate):  # a few flips leave the voxels as they were (padding bits, unused codes)
    try:
        zlib.decompress(candidate[data_start:])
        return False
    except zlib.error:
        return True


flipped = next(f for f in map(flipped_at, range(len(mha) // 2, len(mha))) if damages(f))
damaged = {"gzip NRRD cut at 97 %": ("cut.nrrd", nrrd[:len(nrrd) * 97 // 100]),
           "gzip NRRD without its last 4 bytes": ("short.nrrd", nrrd[:-4]),
           "zlib MetaImage with a flipped byte": ("flipped.mha", flipped)}
for f in os.listdir(f"{work}/mhd"):
    data = open(f"{work}/mhd/{f}", "rb").read()
    open(f"{work}/damaged/{f}", "wb").write(data[:len(data) // 2] if f.endswith(".zraw") else data)
damaged_paths = {"MetaImage whose .zraw is cut in half": f"{work}/damaged/posed_labels.mhd"}
for what, (name, data) in damaged.items():
    damaged_paths[what] = f"{work}/damaged/{name}"
    open(damaged_paths[what], "wb").write(data)
for i, (what, path) in enumerate(damaged_paths.items()):
    try:
        Image(path)
        message = None
    except RuntimeError as e:
        message = str(e)
    check(message is not None and "\n" not in message and os.path.basename(path) in message,
          f"{what}: the reader refuses it: {message}", failures)
    expect_refusal(what, ["prepare", "--labels", path, "--skeleton", f"{TINY}/phantom/skeleton.json"],
                   os.path.basename(path), f"{work}/out{i}", failures)
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
