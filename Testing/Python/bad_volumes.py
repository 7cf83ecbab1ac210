"""Damaged and hostile label volumes: each refused on read with one line naming the file, before any
allocation sized by the damage, with no output left and the input unchanged. The bad files are made
from the tiny phantom by editing bytes (NIfTI header fields, gzip streams, NRRD and MetaImage data)."""
import bz2
import gzip
import os
import shutil
import struct
import sys
import zlib

import numpy as np

from repose_testing import TEMP, TINY, Image, check, expect_refusal, file_digests

work = os.path.join(TEMP, "bad_volumes")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/in")
failures = []
skeleton = f"{TINY}/phantom/skeleton.json"
nifti = gzip.decompress(open(f"{TINY}/phantom/labels.nii.gz", "rb").read())
# The phantom's labels are written in the smallest integer type; the damage below is done to an int32
# copy (NIfTI datatype 8), whose header fields and voxel bytes the edits address.
datatype = struct.unpack_from("<h", nifti, 70)[0]
labels = np.frombuffer(nifti[352:], {2: np.uint8, 4: np.int16, 512: np.uint16, 8: np.int32}[datatype]).astype(np.int32)
header = bytearray(nifti[:352])
struct.pack_into("<hh", header, 70, 8, 32)
header, voxels = bytes(header), labels.tobytes()
nifti = header + voxels


def put(name, data, compress=None):
    path = f"{work}/in/{name}"
    with open(path, "wb") as f:
        f.write(gzip.compress(data, mtime=0) if (compress if compress is not None else name.endswith(".gz")) else data)
    return path


def edited(fmt, offset, *values, data=None):
    """The phantom's NIfTI bytes with header field `fmt` at `offset` replaced."""
    h = bytearray(header)
    struct.pack_into("<" + fmt, h, offset, *values)
    return bytes(h) + (voxels if data is None else data)


def with_datatype(code, bits, array):
    return edited("hh", 70, code, bits, data=np.ascontiguousarray(array).tobytes())


gz = gzip.compress(nifti, mtime=0)
crc = bytearray(gz)
crc[-6] ^= 0xFF  # a CRC-32 byte of the trailer
size = bytearray(gz)
size[-2] ^= 0x01  # ISIZE, the length modulo 2^32
body = bytearray(gz)
body[len(gz) // 2] ^= 0x55  # a byte in the middle of the deflate stream
dims = struct.unpack_from("<8h", header, 40)
one_bone = labels.copy()
bone = int(np.max(labels))  # a bone label of the phantom's skeleton (ids are above the soft tissue's)
one_bone[one_bone == bone] = 0
nan_labels = labels.astype(np.float32)
nan_labels[len(nan_labels) // 2] = np.nan
inf_labels = labels.astype(np.float32)
inf_labels[7] = np.inf
wide = labels.astype(np.uint32)
wide[labels.argmax()] = 3_000_000_000
huge = labels.copy()
huge[labels.argmax()] = 2**31 - 1
negative = labels.copy()
negative[3] = -4

nrrd_text = ("NRRD0004\ntype: int\ndimension: 3\nsizes: {} {} {}\nspacings: 8 8 10\nendian: little\n"
             "encoding: {}\n\n").format(*dims[1:4], "{}")
mha_text = ("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
            "{}\nElementSpacing = 8 8 10\nDimSize = {} {} {}\nElementType = MET_INT\n"
            "ElementDataFile = LOCAL\n").format("{}", *dims[1:4])
cut = len(voxels) * 97 // 100


def compressed_mha(data):
    return mha_text.format(f"CompressedData = True\nCompressedDataSize = {len(data)}").encode() + data


def nifti_pair(name, data):
    """A two-file NIfTI: NAME.hdr (magic ni1, voxels from byte 0 of the .img) and NAME.img; the .hdr's path."""
    h = bytearray(header[:348])
    struct.pack_into("<f", h, 108, 0.0)
    h[344:348] = b"ni1\0"
    if data is not None:
        put(f"{name}.img", data)
    return put(f"{name}.hdr", bytes(h))


def detached_nrrd(name, encoding, data, data_name):
    put(data_name, data)
    return put(name, (nrrd_text.format(encoding).rstrip("\n") + f"\ndata file: {data_name}\n").encode())


ascii_voxels = "\n".join(map(str, labels)).encode() + b"\n"
ascii_cut = b"\n".join(ascii_voxels.split()[:len(labels) * 97 // 100]) + b"\n"
hex_voxels = "\n".join(voxels[i:i + 32].hex() for i in range(0, len(voxels), 32)).encode() + b"\n"


bad = {
    # integrity: cut, corrupted, or promising more than it holds
    "cut at 97 % (gzip)": put("cut97.nii.gz", gz[:len(gz) * 97 // 100], False),
    "cut at 50 % (gzip)": put("cut50.nii.gz", gz[:len(gz) // 2], False),
    "cut inside the header (gzip)": put("cut_header.nii.gz", gz[:40], False),
    "gzip CRC damaged": put("crc.nii.gz", bytes(crc), False),
    "gzip length damaged": put("isize.nii.gz", bytes(size), False),
    "deflate stream damaged": put("body.nii.gz", bytes(body), False),
    "header claims twice the slices (gzip)": put("slices.nii.gz", edited("h", 46, dims[3] * 2)),
    "cut at 97 % (.nii)": put("cut97.nii", nifti[:352 + cut]),
    "header claims twice the slices (.nii)": put("slices.nii", edited("h", 46, dims[3] * 2)),
    "header claims 2^45 voxels": put("vast.nii.gz", edited("hhh", 42, 32000, 32000, 32000)),
    "empty file": put("empty.nii.gz", b"", False),
    "voxel offset 1e9": put("offset.nii.gz", edited("f", 108, 1e9)),
    "negative dimension": put("negative_dim.nii.gz", edited("h", 42, -5)),
    "four dimensions": put("time.nii.gz", edited("hhhhhh", 40, 4, dims[1], dims[2], dims[3] // 2, 2, 1,
                                                 data=voxels[:dims[1] * dims[2] * (dims[3] // 2) * 2 * 4])),
    "detached NRRD without its data file": put("lost.nhdr", (nrrd_text.format("raw").rstrip("\n") +
                                                             "\ndata file: lost.raw\n").encode()),
    "random bytes": put("random.nii.gz", np.random.default_rng(1).bytes(4096), False),
    "NRRD cut short (raw)": put("cut.nrrd", nrrd_text.format("raw").encode() + voxels[:cut]),
    "NRRD gzip data cut short": put("cut_gz.nrrd", nrrd_text.format("gzip").encode() +
                                    gzip.compress(voxels, mtime=0)[:-100]),
    "NRRD gzip data of too few voxels": put("few_gz.nrrd", nrrd_text.format("gzip").encode() +
                                            gzip.compress(voxels[:cut], mtime=0)),
    "MetaImage cut short": put("cut.mha", mha_text.format("CompressedData = False").encode() + voxels[:cut]),
    "MetaImage zlib data damaged": put("zlib.mha", compressed_mha(zlib.compress(voxels)[:-9] + b"\0" * 9)),
    "two-file NIfTI, .img cut at 97 %": nifti_pair("pair_cut", voxels[:cut]),
    "two-file NIfTI named by its .img, cut": nifti_pair("pair_img_cut", voxels[:cut])[:-4] + ".img",
    "two-file NIfTI without its .img": nifti_pair("pair_lost", None),
    "NRRD ascii data cut short": put("cut_ascii.nrrd", nrrd_text.format("ascii").encode() + ascii_cut),
    "NRRD hex data cut short": put("cut_hex.nrrd", nrrd_text.format("hex").encode() + hex_voxels[:len(hex_voxels) * 97 // 100]),
    "NRRD bzip2 data (not readable)": put("bzip2.nrrd", nrrd_text.format("bzip2").encode() + bz2.compress(voxels)),
    "detached NRRD, .raw cut short": detached_nrrd("cut_raw.nhdr", "raw", voxels[:cut], "cut_raw.raw"),
    "detached NRRD, ascii data cut short": detached_nrrd("cut_ascii.nhdr", "ascii", ascii_cut, "cut_ascii.txt"),
    # grids no scanner makes
    "NaN spacing": put("nan_spacing.nii.gz", edited("f", 80, float("nan"))),
    "spacing 1e30 mm": put("vast_spacing.nii.gz", edited("fff", 80, 1e30, 1e30, 1e30)),
    "zero spacing": put("zero_spacing.nii.gz", edited("f", 84, 0.0)),
    "negative spacing": put("negative_spacing.nii.gz", edited("f", 88, -10.0)),
    "infinite origin (qform)": put("inf_qform.nii.gz", edited("f", 268, float("inf"))),
    "NaN direction (sform)": put("nan_sform.nii.gz", edited("f", 284, float("nan"))),
    "NRRD NaN direction": put("nan_direction.nrrd", nrrd_text.format("raw").replace(
        "spacings: 8 8 10", "space directions: (8,0,0) (0,nan,0) (0,0,10)").encode() + voxels),
    "MetaImage infinite direction": put("inf_direction.mha", mha_text.format("CompressedData = False").replace(
        "ElementSpacing", "TransformMatrix = 1 0 0 0 inf 0 0 0 1\nElementSpacing").encode() + voxels),
    "NRRD NaN spacing": put("nan_spacing.nrrd", nrrd_text.format("raw").replace("8 8 10", "8 nan 10").encode()
                            + voxels),
    "MetaImage origin 1e300": put("far.mha", mha_text.format("CompressedData = False").replace(
        "ElementSpacing", "Offset = 0 1e300 0\nElementSpacing").encode() + voxels),
    "MetaImage singular direction": put("flat.mha", mha_text.format("CompressedData = False").replace(
        "ElementSpacing", "TransformMatrix = 1 0 0 1 0 0 0 0 1\nElementSpacing").encode() + voxels),
    # values no label volume holds
    "uint32 label 3 000 000 000": put("wide.nii.gz", with_datatype(768, 32, wide)),
    "label 2^31-1": put("huge_label.nii.gz", edited("h", 70, 8, data=huge.tobytes())),
    "negative label": put("negative_label.nii.gz", edited("h", 70, 8, data=negative.tobytes())),
    "NaN voxel (float)": put("nan_voxel.nii.gz", with_datatype(16, 32, nan_labels)),
    "infinite voxel (float)": put("inf_voxel.nii.gz", with_datatype(16, 32, inf_labels)),
    "NaN voxel (double, .nii)": put("nan_voxel.nii", with_datatype(64, 64, nan_labels.astype(np.float64))),
    "NaN voxel (float, NRRD)": put("nan_voxel.nrrd", nrrd_text.format("raw").replace("type: int", "type: float")
                                   .encode() + nan_labels.tobytes()),
}
# A header extension moves the voxels (vox_offset 368); gzip members may be concatenated.
extended = bytearray(header)
struct.pack_into("<f", extended, 108, 368.0)
struct.pack_into("<4b", extended, 348, 1, 0, 0, 0)
extended = bytes(extended) + struct.pack("<ii", 16, 6) + b"comment\0" + voxels
members = gzip.compress(nifti[:1000], mtime=0) + gzip.compress(nifti[1000:], mtime=0)
# A file whose damage removed a bone: it is read, but the missing bone is the volume's fault.
gone = put("bone_gone.nii.gz", edited("h", 70, 8, data=one_bone.tobytes()))
# The undamaged variants are read: the checks refuse damage, not formats.
good = {put("good.nii", nifti): labels, put("good.nrrd", nrrd_text.format("raw").encode() + voxels): labels,
        put("good_gz.nrrd", nrrd_text.format("gzip").encode() + gzip.compress(voxels, mtime=0)): labels,
        put("good.mha", compressed_mha(zlib.compress(voxels))): labels,
        nifti_pair("good_pair", voxels): labels, nifti_pair("good_pair_img", voxels)[:-4] + ".img": labels,
        put("good_ascii.nrrd", nrrd_text.format("ascii").encode() + ascii_voxels): labels,
        put("good_hex.nrrd", nrrd_text.format("hex").encode() + hex_voxels): labels,
        detached_nrrd("good_raw.nhdr", "raw", voxels, "good_raw.raw"): labels,
        detached_nrrd("good_ascii.nhdr", "ascii", ascii_voxels, "good_ascii.txt"): labels,
        put("good_float.nii.gz", with_datatype(16, 32, labels.astype(np.float32))): labels,
        put("good_wide.nii.gz", with_datatype(768, 32, labels.astype(np.uint32))): labels,
        put("good_extension.nii.gz", extended): labels, put("good_members.nii.gz", members, False): labels,
        gone: one_bone}
for path, expected in good.items():
    check(np.array_equal(Image(path).a.ravel(), expected), f"undamaged {os.path.basename(path)} is read", failures)

before = file_digests(f"{work}/in")
# What the refusals of damaged data files must say (not the image library's own words).
reasons = {"two-file NIfTI, .img cut at 97 %": "data file ", "two-file NIfTI named by its .img, cut": "holds",
           "two-file NIfTI without its .img": "pair_lost.img is missing", "NRRD ascii data cut short": "values",
           "NRRD hex data cut short": "hex digits", "NRRD bzip2 data (not readable)": "save it raw or gzip",
           "detached NRRD, .raw cut short": "data file ", "detached NRRD, ascii data cut short": "cut_ascii.txt: "}
for i, (what, path) in enumerate(bad.items()):
    line = expect_refusal(what, ["prepare", "--labels", path, "--skeleton", skeleton], os.path.basename(path),
                          f"{work}/out{i}", failures)
    if what in reasons:
        check(reasons[what] in line, f"{what}: the reason says {reasons[what]!r}", failures)
line = expect_refusal("bone removed by damage", ["prepare", "--labels", gone, "--skeleton", skeleton],
                      "bone_gone.nii.gz", f"{work}/out_gone", failures)
check(line.startswith(f"repose: error: {gone}") and "absent" in line, "the volume is blamed first", failures)
# Voxelize reads references and the GUI reads scans through the same reader.
expect_refusal("damaged voxelize reference", ["voxelize", "--skin", f"{TINY}/case/surfaces.vtp",
                                              "--reference", bad["cut at 97 % (gzip)"]],
               "cut97.nii.gz", f"{work}/voxelized.nii.gz", failures)
check(file_digests(f"{work}/in") == before, "inputs unchanged", failures)
print(f"bad volumes tried: {len(bad) + 2}")
print(f"{len(bad) + len(good) + len(reasons) + 4 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
