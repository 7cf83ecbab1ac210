"""The figures a batch records per posed result: body volume ratio and inverted tets of the posed tet
mesh, and each bone's Dice between the posed label volume and its rest voxels moved rigidly (the
motion its fixed nodes took, fitted by Kabsch), the worst of them kept."""
import json

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy


def tet_volumes(points, tets):
    """Signed volumes (mm^3) of tets (#T by 4) over points (#V by 3)."""
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def _points(data_set):
    return vtk_to_numpy(data_set.GetPoints().GetData()).astype(np.float64)


def _grid(image):
    """(labels[k, j, i], origin, spacing, direction) of a volume."""
    d = image.GetDimensions()
    m = image.GetDirectionMatrix()
    direction = np.array([[m.GetElement(r, c) for c in range(3)] for r in range(3)])
    values = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(d[2], d[1], d[0])
    return values, np.array(image.GetOrigin()), np.array(image.GetSpacing()), direction


def _kabsch(a, b):
    """Rotation R and translation t best taking points a onto b (both #N by 3)."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    R = vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    return R, cb - R @ ca


class RestFigures:
    """What the figures need of a case, computed once: rest tets and volume, bones and their voxels."""

    def __init__(self, rest_mesh, rest_labels, skeleton_json):
        self.tets = vtk_to_numpy(rest_mesh.GetCells().GetConnectivityArray()).reshape(-1, 4)
        self.rest_points = _points(rest_mesh)
        self.rest_volume = tet_volumes(self.rest_points, self.tets).sum()
        self.fixed = vtk_to_numpy(rest_mesh.GetPointData().GetArray("FixedBone"))
        self.labels, self.origin, self.spacing, self.direction = _grid(rest_labels)
        self.bones = []  # (joint name, its fixed nodes, its labels, its rest voxel centres)
        for index, joint in enumerate(json.loads(skeleton_json)["joints"]):
            nodes = np.flatnonzero(self.fixed == index)
            voxels = np.argwhere(np.isin(self.labels, joint["labels"]))[:, ::-1]  # (i, j, k)
            if len(nodes) >= 3 and len(voxels):
                centres = (voxels * self.spacing) @ self.direction.T + self.origin
                self.bones.append((joint["name"], nodes, joint["labels"], centres))

    def rest_lookup(self, points):
        """Rest labels at the nearest voxels of physical points (#N by 3); 0 outside the volume."""
        ijk = np.rint(((points - self.origin) @ self.direction) / self.spacing).astype(np.int64)
        dims = np.array(self.labels.shape[::-1])
        inside = np.all((ijk >= 0) & (ijk < dims), axis=1)
        out = np.zeros(len(points), dtype=self.labels.dtype)
        c = ijk[inside]
        out[inside] = self.labels[c[:, 2], c[:, 1], c[:, 0]]
        return out

    def figures(self, posed_mesh, posed_labels):
        posed_points = _points(posed_mesh)
        volumes = tet_volumes(posed_points, self.tets)
        result = {"body_volume_ratio": float(volumes.sum() / self.rest_volume),
                  "inverted_tets": int((volumes <= 0).sum()), "worst_bone": "", "worst_bone_dice": None}
        labels, origin, spacing, direction = _grid(posed_labels)
        dims = np.array(labels.shape[::-1])
        for name, nodes, bone_labels, centres in self.bones:
            R, t = _kabsch(self.rest_points[nodes], posed_points[nodes])
            got_all = int(np.isin(labels, bone_labels).sum())
            # Posed voxels the moved bone can reach: the box of its moved rest voxels, one voxel wider.
            ijk = (((centres @ R.T + t) - origin) @ direction) / spacing
            lo = np.clip(np.floor(ijk.min(0)).astype(int) - 1, 0, dims - 1)
            hi = np.clip(np.ceil(ijk.max(0)).astype(int) + 1, 0, dims - 1)
            box = labels[lo[2]:hi[2] + 1, lo[1]:hi[1] + 1, lo[0]:hi[0] + 1]
            k, j, i = np.meshgrid(*(np.arange(lo[a], hi[a] + 1) for a in (2, 1, 0)), indexing="ij")
            x = (np.stack([i, j, k], -1).reshape(-1, 3) * spacing) @ direction.T + origin
            expected = np.isin(self.rest_lookup((x - t) @ R), bone_labels)  # R^T (x - t)
            got = np.isin(box.reshape(-1), bone_labels)
            total = got_all + int(expected.sum())
            dice = 1.0 if total == 0 else 2.0 * int((got & expected).sum()) / total
            if result["worst_bone_dice"] is None or dice < result["worst_bone_dice"]:
                result["worst_bone"], result["worst_bone_dice"] = name, dice
        return result
