#include "rigid_bone_overlay.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "label_boxes.h"
#include "parallel_for.h"

namespace repose {
namespace {

bool nearestVoxel(const ImageGrid& g, const Eigen::Vector3d& x, std::size_t& index) {
  const Eigen::Vector3d f = g.physicalToIndex(x);
  const long i = std::lround(f.x()), j = std::lround(f.y()), k = std::lround(f.z());
  if (!g.contains(int(i), int(j), int(k))) return false;
  index = g.linearIndex(int(i), int(j), int(k));
  return true;
}

}  // namespace

std::vector<RigidBone> rigidBonesFromMesh(const LabelVolume& rest, const Points& restNodes,
                                          const Points& posedNodes, const std::vector<int>& fixedBone) {
  if (restNodes.rows() != posedNodes.rows() || fixedBone.size() != std::size_t(restNodes.rows()))
    throw std::invalid_argument("rigid bones: rest nodes, posed nodes and fixed bones differ in count");
  int boneCount = 0;
  for (int b : fixedBone) boneCount = std::max(boneCount, b + 1);
  std::vector<std::vector<Eigen::Index>> nodesOf(static_cast<std::size_t>(boneCount));
  for (Eigen::Index v = 0; v < restNodes.rows(); ++v)
    if (fixedBone[std::size_t(v)] >= 0) nodesOf[std::size_t(fixedBone[std::size_t(v)])].push_back(v);

  std::vector<RigidBone> bones;
  for (const auto& nodes : nodesOf) {
    if (nodes.size() < 3) continue;
    Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
    for (Eigen::Index v : nodes) {
      ca += restNodes.row(v).transpose();
      cb += posedNodes.row(v).transpose();
    }
    ca /= double(nodes.size());
    cb /= double(nodes.size());
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero(), spread = Eigen::Matrix3d::Zero();
    for (Eigen::Index v : nodes) {
      const Eigen::Vector3d a = restNodes.row(v).transpose() - ca;
      H += a * (posedNodes.row(v).transpose() - cb).transpose();
      spread += a * a.transpose();
    }
    // Collinear (or coincident) nodes do not fix a rotation.
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
    if (!(ev[1] > 1e-9 * std::max(1.0, ev[2]))) continue;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
    RigidBone bone;
    const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
    bone.transform.linear() = R;
    bone.transform.translation() = cb - R * ca;
    std::set<std::int32_t> labels;
    for (Eigen::Index v : nodes) {
      std::size_t index;
      if (nearestVoxel(rest.grid, restNodes.row(v).transpose(), index) && rest.data[index] != 0)
        labels.insert(rest.data[index]);
    }
    bone.labels.assign(labels.begin(), labels.end());
    if (!bone.labels.empty()) bones.push_back(std::move(bone));
  }
  return bones;
}

std::size_t overlayRigidBones(LabelVolume& posed, const LabelVolume& rest, const std::vector<RigidBone>& bones) {
  if (posed.data.size() != posed.grid.voxelCount())
    throw std::invalid_argument("rigid bones: volume sizes do not match their grids");
  return overlayRigidBones(posed.data.data(), posed.grid, rest, bones);
}

std::vector<Eigen::AlignedBox3i> restLabelBoxes(const LabelVolume& rest) {
  if (rest.data.size() != rest.grid.voxelCount())
    throw std::invalid_argument("rigid bones: volume sizes do not match their grids");
  return labelBoxes(rest);
}

std::size_t overlayRigidBones(std::int32_t* posedData, const ImageGrid& posedGrid, const LabelVolume& rest,
                              const std::vector<RigidBone>& bones) {
  return overlayRigidBones(posedData, posedGrid, rest, bones, nullptr);
}

std::size_t overlayRigidBones(std::int32_t* posedData, const ImageGrid& posedGrid, const LabelVolume& rest,
                              const std::vector<RigidBone>& bones,
                              const std::vector<Eigen::AlignedBox3i>* labelBoxes, std::size_t* contestedVoxels) {
  if (rest.data.size() != rest.grid.voxelCount())
    throw std::invalid_argument("rigid bones: volume sizes do not match their grids");
  if (!posedData && posedGrid.voxelCount() > 0) throw std::invalid_argument("rigid bones: null posed volume");
  std::int32_t maxLabel = 0;
  for (const auto& b : bones)
    for (auto l : b.labels) maxLabel = std::max(maxLabel, l);
  // Which bone each label belongs to (-1: not bone), and each bone's rest bounding box in index space.
  std::vector<int> boneOfLabel(std::size_t(maxLabel) + 1, -1);
  for (std::size_t b = 0; b < bones.size(); ++b)
    for (auto l : bones[b].labels)
      if (l >= 0) boneOfLabel[std::size_t(l)] = int(b);
  const auto& rd = rest.grid.dims;
  std::vector<Eigen::AlignedBox3i> restBox(bones.size());
  if (labelBoxes && !labelBoxes->empty()) {
    // A bone's box is the union of its labels' boxes.
    for (std::size_t b = 0; b < bones.size(); ++b)
      for (auto l : bones[b].labels)
        if (l > 0 && boneOfLabel[std::size_t(l)] == int(b) && std::size_t(l) < labelBoxes->size() &&
            !(*labelBoxes)[std::size_t(l)].isEmpty())
          restBox[b].extend((*labelBoxes)[std::size_t(l)]);
  } else {
    // Bounding boxes in fixed chunks of slices, in parallel, then merged.
    const std::size_t nChunks = std::max<std::size_t>(1, std::min<std::size_t>(64, std::size_t(rd[2])));
    std::vector<std::vector<Eigen::AlignedBox3i>> chunkBox(nChunks, std::vector<Eigen::AlignedBox3i>(bones.size()));
    parallelFor(nChunks, [&](std::size_t cb, std::size_t ce) {
      for (std::size_t c = cb; c < ce; ++c) {
        auto& box = chunkBox[c];
        for (int k = int(c * std::size_t(rd[2]) / nChunks); k < int((c + 1) * std::size_t(rd[2]) / nChunks); ++k)
          for (int j = 0; j < rd[1]; ++j) {
            const std::int32_t* row = rest.data.data() + rest.grid.linearIndex(0, j, k);
            for (int i = 0; i < rd[0]; ++i) {
              const std::int32_t l = row[i];
              if (l > 0 && l <= maxLabel && boneOfLabel[std::size_t(l)] >= 0)
                box[std::size_t(boneOfLabel[std::size_t(l)])].extend(Eigen::Vector3i(i, j, k));
            }
          }
      }
    }, 1);
    for (const auto& box : chunkBox)
      for (std::size_t b = 0; b < bones.size(); ++b)
        if (!box[b].isEmpty()) restBox[b].extend(box[b]);
  }
  auto isBone = [&](std::int32_t l) { return l > 0 && l <= maxLabel && boneOfLabel[std::size_t(l)] >= 0; };

  // The rest label that bone `other`'s rigid motion brings to output voxel (i, j, k).
  auto restLabelUnder = [&](std::size_t other, int i, int j, int k) -> std::int32_t {
    std::size_t index;
    const Eigen::Vector3d x = bones[other].transform.inverse() * posedGrid.indexToPhysical(Eigen::Vector3d(i, j, k));
    return nearestVoxel(rest.grid, x, index) ? rest.data[index] : 0;
  };

  std::atomic<std::size_t> changed{0}, contested{0};
  const auto& od = posedGrid.dims;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    if (restBox[b].isEmpty()) continue;
    const Eigen::Isometry3d& G = bones[b].transform;
    const Eigen::Isometry3d Ginv = G.inverse();
    // Output index box of the moved rest box (one voxel of margin).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1 ? restBox[b].max().x() + 1.0 : restBox[b].min().x() - 1.0),
                                   (c & 2 ? restBox[b].max().y() + 1.0 : restBox[b].min().y() - 1.0),
                                   (c & 4 ? restBox[b].max().z() + 1.0 : restBox[b].min().z() - 1.0));
      const Eigen::Vector3d o = posedGrid.physicalToIndex(G * rest.grid.indexToPhysical(corner));
      lo = lo.cwiseMin(o);
      hi = hi.cwiseMax(o);
    }
    int lo3[3], hi3[3];
    for (int a = 0; a < 3; ++a) {
      lo3[a] = std::max(0, int(std::floor(lo[a])));
      hi3[a] = std::min(od[a] - 1, int(std::ceil(hi[a])));
    }
    if (lo3[0] > hi3[0] || lo3[1] > hi3[1] || lo3[2] > hi3[2]) continue;
    // Output index -> rest continuous index is affine.
    const Eigen::Matrix3d toRest = rest.grid.spacing.cwiseInverse().asDiagonal() * rest.grid.direction.transpose() *
                                   Ginv.linear() * posedGrid.direction * posedGrid.spacing.asDiagonal();
    const Eigen::Vector3d restOfOrigin =
        rest.grid.physicalToIndex(Ginv * posedGrid.indexToPhysical(Eigen::Vector3d::Zero()));
    parallelFor(std::size_t(hi3[2] - lo3[2] + 1), [&](std::size_t kb, std::size_t ke) {
      std::size_t local = 0, localContested = 0;
      for (int k = lo3[2] + int(kb); k < lo3[2] + int(ke); ++k)
        for (int j = lo3[1]; j <= hi3[1]; ++j) {
          Eigen::Vector3d r = restOfOrigin + toRest * Eigen::Vector3d(lo3[0], j, k);
          const Eigen::Vector3d step = toRest.col(0);
          std::int32_t* outRow = posedData + posedGrid.linearIndex(0, j, k);
          for (int i = lo3[0]; i <= hi3[0]; ++i, r += step) {
            // Nearest rest voxel, rounding halves away from zero (as lround): inside iff -0.5 < r < d - 0.5.
            const bool inRest = r.x() > -0.5 && r.y() > -0.5 && r.z() > -0.5 && r.x() < rd[0] - 0.5 &&
                                r.y() < rd[1] - 0.5 && r.z() < rd[2] - 0.5;
            const std::int32_t restLabel =
                inRest ? rest.data[rest.grid.linearIndex(int(r.x() + 0.5), int(r.y() + 0.5), int(r.z() + 0.5))] : 0;
            std::int32_t& out = outRow[i];
            const bool restIsThisBone = isBone(restLabel) && boneOfLabel[std::size_t(restLabel)] == int(b);
            const bool outIsThisBone = isBone(out) && boneOfLabel[std::size_t(out)] == int(b);
            std::int32_t value = out;
            if (restIsThisBone) {
              value = restLabel;
              // Counted once, by the later of the two bones: the earlier one's label is here by then.
              if (contestedVoxels && isBone(out) && boneOfLabel[std::size_t(out)] < int(b)) {
                const std::size_t other = std::size_t(boneOfLabel[std::size_t(out)]);
                const std::int32_t under = restLabelUnder(other, i, j, k);
                if (isBone(under) && boneOfLabel[std::size_t(under)] == int(other)) ++localContested;
              }
            }
            else if (outIsThisBone && !isBone(restLabel))
              value = restLabel;
            if (value != out) {
              out = value;
              ++local;
            }
          }
        }
      changed += local;
      contested += localContested;
    }, 1);
  }
  if (contestedVoxels) *contestedVoxels = contested.load();
  return changed.load();
}

}  // namespace repose
