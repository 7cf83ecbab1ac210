"""Helpers shared by the Python tests: paths, running the CLI, images as numpy arrays, and an
independent forward-kinematics oracle (so the tests do not check the code with itself)."""
import json
import os
import subprocess
import sys

import numpy as np
from scipy import ndimage
from vtkmodules.util.numpy_support import vtk_to_numpy

EXE = os.environ["REPOSE_EXE"]
SHARED = os.environ["REPOSE_SHARED_DATA"]
TESTING = os.environ["REPOSE_TESTING_DIR"]
TEMP = os.environ["REPOSE_TEMP"]
TINY = os.path.join(TEMP, "tiny")  # the fixture's working folder


def run(*args, check=True):
    """Runs the repose CLI; returns (exit code, stdout, stderr)."""
    p = subprocess.run([EXE, *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        sys.exit(f"repose {' '.join(map(str, args))} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p.returncode, p.stdout, p.stderr


class Image:
    """A volume as a numpy array a[k, j, i] with its grid (origin, spacing, direction)."""

    def __init__(self, path):
        from repose import vtkReposeImageReader
        r = vtkReposeImageReader()
        r.SetFileName(path)
        r.Update()
        err = r.GetLastError()
        if err:
            raise RuntimeError(err)
        img = r.GetOutput()
        self.dims = img.GetDimensions()
        self.origin = np.array(img.GetOrigin())
        self.spacing = np.array(img.GetSpacing())
        m = img.GetDirectionMatrix()
        self.direction = np.array([[m.GetElement(r_, c) for c in range(3)] for r_ in range(3)])
        d = self.dims
        self.a = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(d[2], d[1], d[0]).copy()

    def centres(self):
        """Physical centres of all voxels, shape (k, j, i, 3)."""
        k, j, i = np.meshgrid(np.arange(self.dims[2]), np.arange(self.dims[1]), np.arange(self.dims[0]),
                              indexing="ij")
        ijk = np.stack([i, j, k], -1).astype(float) * self.spacing
        return ijk @ self.direction.T + self.origin

    def nearest(self, points, outside=0):
        """Values at the nearest voxel of physical points (..., 3)."""
        ijk = np.rint(((points - self.origin) @ self.direction) / self.spacing).astype(np.int64)
        inside = np.all((ijk >= 0) & (ijk < np.array(self.dims)), axis=-1)
        out = np.full(points.shape[:-1], outside, dtype=self.a.dtype)
        c = ijk[inside]
        out[inside] = self.a[c[:, 2], c[:, 1], c[:, 0]]
        return out


def quat_from_pose_entry(e):
    if "quaternion" in e:
        q = np.array(e["quaternion"], float)
        return q / np.linalg.norm(q)
    axis = np.array(e["axis"], float)
    axis /= np.linalg.norm(axis)
    h = np.radians(e["degrees"]) / 2
    return np.concatenate([[np.cos(h)], np.sin(h) * axis])


def quat_matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def bone_transforms(skeleton, pose):
    """name -> 4x4 rest-to-posed transform, G_j = G_parent T(c) R T(-c) (DESIGN.md)."""
    joints = {j["name"]: j for j in skeleton["joints"]}
    out = {}

    def g(name):
        if name in out:
            return out[name]
        j = joints[name]
        c = np.array(j["center"], float)
        local = np.eye(4)
        if name in pose.get("rotations", {}):
            R = quat_matrix(quat_from_pose_entry(pose["rotations"][name]))
            local[:3, :3] = R
            local[:3, 3] = c - R @ c
        if j["parent"] is None:
            t = np.eye(4)
            t[:3, 3] = pose.get("translation", [0, 0, 0])
            out[name] = t @ local
        else:
            out[name] = g(j["parent"]) @ local
        return out[name]

    for n in joints:
        g(n)
    return out


def load_json(path):
    with open(path) as f:
        return json.load(f)


def dice(a, b):
    s = a.sum() + b.sum()
    return 1.0 if s == 0 else 2.0 * np.logical_and(a, b).sum() / s


def rigid_bone_dice(rest, posed, labels, G):
    """Dice between the posed volume's voxels of `labels` and the rest bone moved rigidly by G."""
    x = posed.centres()
    back = (x - G[:3, 3]) @ G[:3, :3]  # G^-1 x for a rigid G
    expected = np.isin(rest.nearest(back), labels)
    got = np.isin(posed.a, labels)
    return dice(got, expected)


def read_mha(path):
    """A MetaImage file read here, not by VTK or ITK: (voxels as a[k, j, i, channel], header fields)."""
    import zlib
    with open(path, "rb") as f:
        data = f.read()
    header, pos = {}, 0
    while True:
        end = data.index(b"\n", pos)
        key, _, value = data[pos:end].decode().partition(" = ")
        header[key.strip()] = value.strip()
        pos = end + 1
        if key.strip() == "ElementDataFile":
            break
    raw = data[pos:]
    if header.get("CompressedData") == "True":
        raw = zlib.decompress(raw)
    dims = [int(d) for d in header["DimSize"].split()]
    channels = int(header.get("ElementNumberOfChannels", "1"))
    dtype = {"MET_FLOAT": np.float32, "MET_INT": np.int32, "MET_SHORT": np.int16, "MET_USHORT": np.uint16,
             "MET_UCHAR": np.uint8}[header["ElementType"]]
    return np.frombuffer(raw, dtype=dtype).reshape(dims[2], dims[1], dims[0], channels), header


def check(cond, message, failures):
    print(("ok   " if cond else "FAIL ") + message)
    if not cond:
        failures.append(message)


def expect_refusal(what, args, name, out, failures):
    """Runs the CLI with `args` + `--out out` and checks the refusal: non-zero exit, one stderr line
    `repose: error: ...` naming `name`, and nothing left in `out`."""
    code, _, stderr = run(*args, "--out", out, check=False)
    lines = [l for l in stderr.splitlines() if l.strip()]
    one_line = len(lines) == 1 and lines[0].startswith("repose: error:")
    names_file = bool(lines) and name in lines[0]
    no_output = not os.path.exists(out) or (os.path.isdir(out) and not os.listdir(out))
    check(code > 0 and one_line and names_file and no_output,
          f"{what}: exit {code}, {len(lines)} line(s) {'naming' if names_file else 'NOT naming'} {name}, "
          f"{'no' if no_output else 'PARTIAL'} output: {lines[0] if lines else ''}", failures)
    return lines[0] if lines else ""


def file_digests(folder):
    """sha256 of every file under `folder`, by relative path (to show inputs were not touched)."""
    import hashlib
    digests = {}
    for root, _, files in os.walk(folder):
        for f in files:
            path = os.path.join(root, f)
            with open(path, "rb") as fh:
                digests[os.path.relpath(path, folder)] = hashlib.sha256(fh.read()).hexdigest()
    return digests


def compare_with_baseline(png_path, name, threshold=10.0):
    """VTK's image comparison of a rendered PNG with Testing/Data/Baseline/<name>.png. A missing
    baseline copies the candidate to Testing/Temporary and fails (inspect it, then copy it)."""
    import shutil
    from vtkmodules.vtkImagingCore import vtkImageDifference
    from vtkmodules.vtkIOImage import vtkPNGReader
    baseline = os.path.join(TESTING, "Data", "Baseline", name + ".png")
    keep = os.path.join(TESTING, "Temporary")
    os.makedirs(keep, exist_ok=True)
    if not os.path.isfile(baseline):
        shutil.copy(png_path, os.path.join(keep, name + ".png"))
        print(f"no baseline {baseline}; candidate written to {keep}/{name}.png")
        return False
    readers = []
    for p in (png_path, baseline):
        r = vtkPNGReader()
        r.SetFileName(p)
        r.Update()
        readers.append(r)
    diff = vtkImageDifference()
    diff.SetInputConnection(readers[0].GetOutputPort())
    diff.SetImageConnection(readers[1].GetOutputPort())
    diff.Update()
    error = diff.GetThresholdedError()
    print(f"{name}: thresholded image error {error:.3f} (threshold {threshold})")
    if error > threshold:
        shutil.copy(png_path, os.path.join(keep, name + ".png"))
        return False
    return True


class Mesh:
    """A tet mesh (.vtu): the VTK grid, node positions (float64, #V by 3) and tets (#T by 4)."""

    def __init__(self, path):
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
        r = vtkXMLUnstructuredGridReader()
        r.SetFileName(path)
        r.Update()
        self.grid = r.GetOutput()
        self.points = vtk_to_numpy(self.grid.GetPoints().GetData()).astype(float)
        self.tets = vtk_to_numpy(self.grid.GetCells().GetConnectivityArray()).reshape(-1, 4)

    def point_array(self, name):
        return vtk_to_numpy(self.grid.GetPointData().GetArray(name))


def kabsch(a, b):
    """The rigid 4x4 transform best taking points a (N by 3) onto b, and the worst residual."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    R = vt.T @ np.diag([1, 1, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    G = np.eye(4)
    G[:3, :3], G[:3, 3] = R, cb - R @ ca
    return G, np.abs((a - ca) @ R.T + cb - b).max()


def label_table(path):
    """A labels.tsv (value, name, kind) as {name: (value, kind)}."""
    with open(path) as f:
        next(f)
        return {name: (int(value), kind) for value, name, kind in (line.split() for line in f)}


def stretched_volume(case, out, limit=3.0, region=None):
    """Rest volume (ml) of the tets whose largest principal stretch exceeds `limit`, and the largest;
    only the tets whose rest centroids (n by 3) `region` keeps, when given."""
    rest, posed = Mesh(f"{case}/mesh.vtu"), Mesh(f"{out}/posed_mesh.vtu")
    t = rest.tets
    if region is not None:
        t = t[region(rest.points[t].mean(1))]

    def edges(p):
        return np.stack([p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]], p[t[:, 3]] - p[t[:, 0]]], -1)

    Dr, Dp = edges(rest.points), edges(posed.points)
    F = Dp @ np.linalg.inv(Dr)
    smax = np.linalg.svd(F, compute_uv=False)[:, 0]
    vol = np.abs(np.linalg.det(Dr)) / 6
    return vol[smax > limit].sum() / 1000.0, smax.max()


def enclosed_background(a):
    """Background voxels (0) of a label array that no path of background joins to the border: holes.
    The body is 6-connected, so background is 26-connected (a crease closed only at its edges is open)."""
    comp, n = ndimage.label(a == 0, structure=np.ones((3, 3, 3)))
    border = set(np.unique(np.concatenate([comp[0].ravel(), comp[-1].ravel(), comp[:, 0].ravel(),
                                           comp[:, -1].ravel(), comp[:, :, 0].ravel(), comp[:, :, -1].ravel()])))
    return np.isin(comp, [c for c in range(1, n + 1) if c not in border]).sum()


def file_hashes(*roots):
    """SHA-256 of every file under the roots (files or folders), by path: inputs before and after."""
    import hashlib
    hashes = {}
    for root in roots:
        paths = [root] if os.path.isfile(root) else [os.path.join(d, f) for d, _, fs in os.walk(root) for f in fs]
        for p in paths:
            with open(p, "rb") as f:
                hashes[p] = hashlib.sha256(f.read()).hexdigest()
    return hashes


def run_file_size_limited(limit_bytes, *args):
    """Runs the CLI with RLIMIT_FSIZE set (prlimit, no Python between fork and exec): a write past
    the limit fails with EFBIG, as on a full disk, without root or a small file system."""
    p = subprocess.run(["prlimit", f"--fsize={limit_bytes}", EXE, *map(str, args)], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def check_failed_cleanly(result, message, gone, failures, what):
    """A refused or failed run: exit code 1, one stderr line `repose: error: ...` containing
    `message`, and none of the paths in `gone` left (outputs, temporary folders)."""
    code, _, err = result
    lines = err.strip().splitlines()
    check(code == 1, f"{what}: exit code 1 (got {code})", failures)
    check(len(lines) == 1 and lines[0].startswith("repose: error: ") and message in lines[0],
          f"{what}: one line with {message!r} (got {err.strip()!r})", failures)
    for path in gone:
        check(not os.path.exists(path), f"{what}: nothing left in {os.path.basename(path)}", failures)


def tiny_pipeline():
    """The tiny phantom's filters wired as in vtkpython: phantom -> mesher -> weights -> skinning, and the
    labelled surfaces bound to the tet mesh. Returns them by name (and the skeleton JSON); nothing is run."""
    from types import SimpleNamespace
    from repose import (vtkReposeBodyMesher, vtkReposeBoneWeights, vtkReposePhantomSource, vtkReposeSkinning,
                        vtkReposeSurfaceBinding, vtkReposeSurfaceExtractor)
    p = SimpleNamespace(phantom=vtkReposePhantomSource(), mesher=vtkReposeBodyMesher(), weights=vtkReposeBoneWeights(),
                        skinning=vtkReposeSkinning(), surfaces=vtkReposeSurfaceExtractor(),
                        binding=vtkReposeSurfaceBinding())
    p.phantom.SetSizeName("tiny")
    p.phantom.Update()
    p.skeleton = p.phantom.GetSkeletonJSON()
    for downstream, upstream in ((p.mesher, p.phantom), (p.weights, p.mesher), (p.skinning, p.weights),
                                 (p.surfaces, p.phantom)):
        downstream.SetInputConnection(upstream.GetOutputPort())
        downstream.SetSkeletonJSON(p.skeleton)
    p.binding.SetInputConnection(0, p.surfaces.GetOutputPort())
    p.binding.SetInputConnection(1, p.weights.GetOutputPort())
    return p
