#include "mesh_voxelizer.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {
namespace {

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// Triangles with their vertices already in the grid's continuous index space.
struct IndexSpaceTriangles {
  const std::vector<openvdb::Vec3d>* points;
  const MeshTriangles* F;
  std::size_t polygonCount() const { return std::size_t(F->rows()); }
  std::size_t pointCount() const { return points->size(); }
  std::size_t vertexCount(std::size_t) const { return 3; }
  void getIndexSpacePoint(std::size_t n, std::size_t v, openvdb::Vec3d& pos) const {
    pos = (*points)[std::size_t((*F)(Eigen::Index(n), int(v)))];
  }
};

void checkGrid(const ImageGrid& grid) {
  if (grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0)
    throw std::invalid_argument("the voxel grid is empty");
  if (!(grid.spacing.minCoeff() > 0) || !grid.spacing.allFinite() || !grid.origin.allFinite())
    throw std::invalid_argument("the voxel grid needs a positive, finite spacing and a finite origin");
  if (std::abs(std::abs(grid.direction.determinant()) - 1.0) > 1e-3)
    throw std::invalid_argument("the voxel grid's direction matrix is not a rotation");
}

void checkMesh(const MeshVertices& V, const MeshTriangles& F) {
  if (V.rows() == 0 || F.rows() == 0) throw std::invalid_argument("the surface has no triangles");
  if (!V.allFinite()) throw std::invalid_argument("the surface has a vertex that is not a finite number");
}

const char* roleName(VoxelizeRole r) {
  switch (r) {
    case VoxelizeRole::Skin: return "skin";
    case VoxelizeRole::Bone: return "bone";
    default: return "tissue";
  }
}

std::string where(const VoxelizePart& p) { return p.source.empty() ? p.name : p.source; }

std::string percent(double f) {
  std::ostringstream s;
  s.precision(f < 0.1 ? 2 : 3);
  s << 100.0 * f << "%";
  return s.str();
}

}  // namespace

namespace {

/// Index box of points in the grid's index space, clipped to the grid; false when empty.
bool indexBox(const std::vector<openvdb::Vec3d>& points, const ImageGrid& grid, std::array<int, 3>& boxMin,
              std::array<int, 3>& boxDims, bool* cut = nullptr) {
  openvdb::Vec3d lo(INFINITY), hi(-INFINITY);
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  bool empty = false;
  for (int a = 0; a < 3; ++a) {
    const int first = std::max(0, int(std::ceil(lo[a])));
    const int last = std::min(grid.dims[a] - 1, int(std::floor(hi[a])));
    if (cut && (lo[a] < -0.5 || hi[a] > grid.dims[a] - 0.5)) *cut = true;
    boxMin[a] = first;
    boxDims[a] = std::max(0, last - first + 1);
    empty |= boxDims[a] == 0;
  }
  return !empty;
}

/// Calls visit(offset in the outer box, inside) for every voxel of `box` (inside the outer box) where
/// the level set of the triangles is negative. Threaded over slices; visit must be thread-safe per voxel.
template <class Visit>
void forInsideVoxels(const std::vector<openvdb::Vec3d>& points, const MeshTriangles& F, float band,
                     const std::array<int, 3>& boxMin, const std::array<int, 3>& boxDims,
                     const std::array<int, 3>& outerMin, const std::array<int, 3>& outerDims, Visit visit) {
  initializeOpenVdb();
  const IndexSpaceTriangles mesh{&points, &F};
  auto transform = openvdb::math::Transform::createLinearTransform(1.0);
  openvdb::FloatGrid::Ptr sdf = openvdb::tools::meshToVolume<openvdb::FloatGrid>(mesh, *transform, band, band);
  const std::size_t nx = std::size_t(outerDims[0]), ny = std::size_t(outerDims[1]);
  parallelFor(
      std::size_t(boxDims[2]),
      [&](std::size_t k0, std::size_t k1) {
        auto acc = sdf->getConstAccessor();
        for (std::size_t k = k0; k < k1; ++k)
          for (int j = 0; j < boxDims[1]; ++j)
            for (int i = 0; i < boxDims[0]; ++i) {
              const openvdb::Coord c(boxMin[0] + i, boxMin[1] + j, boxMin[2] + int(k));
              if (acc.getValue(c) < 0.0f)
                visit((std::size_t(c.z() - outerMin[2]) * ny + std::size_t(c.y() - outerMin[1])) * nx +
                      std::size_t(c.x() - outerMin[0]));
            }
      },
      1);
}

double signedVolume(const MeshVertices& V, const MeshTriangles& F) {
  const Eigen::RowVector3d c = V.colwise().mean();
  double six = 0;
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const Eigen::Vector3d a = (V.row(F(t, 0)) - c).transpose(), b = (V.row(F(t, 1)) - c).transpose(),
                          d = (V.row(F(t, 2)) - c).transpose();
    six += a.dot(b.cross(d));
  }
  return six / 6.0;
}

std::vector<openvdb::Vec3d> toIndexSpace(const MeshVertices& V, const ImageGrid& grid) {
  std::vector<openvdb::Vec3d> points(std::size_t(V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d p = grid.physicalToIndex(V.row(v).transpose());
    points[std::size_t(v)] = openvdb::Vec3d(p.x(), p.y(), p.z());
  }
  return points;
}

}  // namespace

MeshVoxelization voxelizeMesh(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                              const MeshVoxelizeOptions& options) {
  checkGrid(grid);
  checkMesh(V, F);
  if (!(options.bandVoxels >= 1.0)) throw std::invalid_argument("the narrow band must be at least one voxel wide");
  MeshVoxelization r;
  r.topology = analyzeMeshTopology(V, F);  // also checks the indices
  const float band = float(options.bandVoxels);
  const std::vector<openvdb::Vec3d> points = toIndexSpace(V, grid);
  if (!indexBox(points, grid, r.boxMin, r.boxDims, &r.cutByGrid)) {
    r.boxDims = {0, 0, 0};
    return r;
  }
  const std::size_t n = std::size_t(r.boxDims[0]) * r.boxDims[1] * r.boxDims[2];
  r.inside.assign(n, 0);
  if (r.topology.components <= 1) {
    forInsideVoxels(points, F, band, r.boxMin, r.boxDims, r.boxMin, r.boxDims,
                    [&](std::size_t o) { r.inside[o] = 1; });
  } else {
    // OpenVDB fills everything the outside cannot reach, which would fill a cavity (a skull's inner
    // surface). So each piece is a level set of its own, counted +1 when it faces the way the largest
    // piece faces and -1 (a cavity) when it faces the other way and lies inside the others; a voxel is
    // inside when the count is positive. Overlapping pieces then make a union, nested ones a shell.
    const std::vector<TriangleMesh> pieces = splitConnectedComponents(V, F);
    std::vector<double> volume(pieces.size());
    std::size_t largest = 0;
    for (std::size_t c = 0; c < pieces.size(); ++c) {
      volume[c] = signedVolume(pieces[c].V, pieces[c].F);
      if (std::abs(volume[c]) > std::abs(volume[largest])) largest = c;
    }
    const double outward = volume[largest] >= 0 ? 1.0 : -1.0;
    std::vector<std::int16_t> count(n, 0);
    std::vector<std::size_t> opposite;
    for (std::size_t c = 0; c < pieces.size(); ++c) {
      if (volume[c] * outward < 0) {
        opposite.push_back(c);
        continue;
      }
      const auto pts = toIndexSpace(pieces[c].V, grid);
      std::array<int, 3> bmin, bdims;
      if (indexBox(pts, grid, bmin, bdims))
        forInsideVoxels(pts, pieces[c].F, band, bmin, bdims, r.boxMin, r.boxDims, [&](std::size_t o) { ++count[o]; });
    }
    for (std::size_t c : opposite) {
      const auto pts = toIndexSpace(pieces[c].V, grid);
      std::array<int, 3> bmin, bdims;
      if (!indexBox(pts, grid, bmin, bdims)) continue;
      std::vector<std::uint8_t> mask(n, 0);
      forInsideVoxels(pts, pieces[c].F, band, bmin, bdims, r.boxMin, r.boxDims, [&](std::size_t o) { mask[o] = 1; });
      std::size_t total = 0, nested = 0;
      for (std::size_t o = 0; o < n; ++o)
        if (mask[o]) ++total, nested += count[o] > 0;
      const bool cavity = total > 0 && double(nested) >= 0.95 * double(total);
      (cavity ? r.cavities : r.invertedPieces) += 1;
      for (std::size_t o = 0; o < n; ++o)
        if (mask[o]) count[o] = std::int16_t(count[o] + (cavity ? -1 : 1));
    }
    for (std::size_t o = 0; o < n; ++o) r.inside[o] = count[o] > 0;
  }
  r.insideVoxels = std::size_t(std::count(r.inside.begin(), r.inside.end(), std::uint8_t(1)));
  return r;
}

ImageGrid gridFittingPoints(const MeshVertices& V, double voxelMm, double padVoxels, std::size_t maxVoxels) {
  if (V.rows() == 0) throw std::invalid_argument("the surface has no vertices");
  if (!V.allFinite()) throw std::invalid_argument("the surface has a vertex that is not a finite number");
  if (!(voxelMm > 0) || !std::isfinite(voxelMm)) throw std::invalid_argument("the voxel size must be positive");
  if (!(padVoxels >= 0)) throw std::invalid_argument("the padding must not be negative");
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  ImageGrid g;
  g.spacing = Eigen::Vector3d::Constant(voxelMm);
  double count = 1;
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil((hi[a] - lo[a]) / voxelMm + 2 * padVoxels) + 1;
    count *= n;
    if (n > 2e9) throw std::invalid_argument("the voxel size is far too small for the surface's size");
    g.dims[a] = int(n);
    // Centre the lattice on the bounds so the padding is equal on both sides.
    g.origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (n - 1) * voxelMm;
  }
  if (count > double(maxVoxels)) {
    const Eigen::Vector3d size = hi - lo;
    const double fit = std::cbrt(size.prod() / double(maxVoxels)) * 1.05;
    std::ostringstream s;
    s << "a " << voxelMm << " mm grid over the skin's bounds (" << size.x() << " x " << size.y() << " x " << size.z()
      << " mm) needs " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << " = " << std::size_t(count)
      << " voxels, above the limit of " << maxVoxels << "; use a voxel size of at least about " << fit
      << " mm or raise the limit";
    throw std::invalid_argument(s.str());
  }
  return g;
}

std::string LabelVoxelization::text() const {
  std::ostringstream s;
  const auto& g = labels.grid;
  s << "grid " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << " voxels of " << g.spacing.x() << " x "
    << g.spacing.y() << " x " << g.spacing.z() << " mm, origin (" << g.origin.x() << ", " << g.origin.y() << ", "
    << g.origin.z() << ")\n";
  for (const auto& p : parts) {
    s << "  " << p.label << " " << p.name << " (" << roleName(p.role) << ", " << (p.source.empty() ? p.name : p.source)
      << "): " << p.topology.triangles << " triangles, " << p.topology.boundaryEdges << " boundary edges, " << p.voxels
      << " voxels (" << p.voxelVolume / 1000.0 << " ml";
    if (p.topology.boundaryEdges == 0 && p.topology.enclosedVolume > 0)
      s << ", mesh " << p.topology.enclosedVolume / 1000.0 << " ml";
    if (p.cavities > 0) s << ", " << p.cavities << " cavities carved";
    s << ")\n";
  }
  for (const auto& w : warnings) s << "warning: " << w << "\n";
  return s.str();
}

LabelVoxelization voxelizeLabels(const std::vector<VoxelizePart>& parts, const ImageGrid& gridIn,
                                 const LabelVoxelizeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const VoxelizePart* skin = nullptr;
  std::set<std::string> names;
  for (const auto& p : parts) {
    if (p.name.empty()) throw std::invalid_argument(where(p) + ": the surface needs a label name");
    if (p.name.find_first_of(" \t\n") != std::string::npos)
      throw std::invalid_argument(where(p) + ": the label name '" + p.name + "' must not contain blanks");
    if (!names.insert(p.name).second) throw std::invalid_argument(where(p) + ": the name '" + p.name + "' is used twice");
    if (p.role == VoxelizeRole::Skin) {
      if (skin) throw std::invalid_argument(where(p) + ": only one skin surface can be given");
      skin = &p;
    }
    try {
      checkMesh(p.V, p.F);
      analyzeMeshTopology(p.V, p.F);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where(p) + ": " + e.what());
    }
  }
  if (!skin) throw std::invalid_argument("a skin surface is needed (it makes the body's soft tissue)");

  LabelVoxelization out;
  ImageGrid grid = gridIn;
  if (grid.voxelCount() == 0) {
    try {
      grid = gridFittingPoints(skin->V, options.voxelMm, options.padVoxels, options.maxVoxels);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where(*skin) + ": " + e.what());
    }
  } else {
    checkGrid(grid);
    if (grid.voxelCount() > options.maxVoxels)
      throw std::invalid_argument("the grid has " + std::to_string(grid.voxelCount()) + " voxels, above the limit of " +
                                  std::to_string(options.maxVoxels));
  }
  const double voxelVolume = grid.spacing.prod();

  // Skin first, then bones, then tissues, each in input order: the label values follow that order.
  std::vector<const VoxelizePart*> order;
  order.push_back(skin);
  for (auto role : {VoxelizeRole::Bone, VoxelizeRole::Tissue})
    for (const auto& p : parts)
      if (p.role == role) order.push_back(&p);

  out.labels.grid = grid;
  out.labels.data.assign(grid.voxelCount(), 0);
  out.table.labels.push_back({0, "background", LabelKind::Background});
  MeshVoxelization skinMask;
  for (std::size_t n = 0; n < order.size(); ++n) {
    const VoxelizePart& p = *order[n];
    const int label = int(n) + 1;
    MeshVoxelization m;
    try {
      m = voxelizeMesh(p.V, p.F, grid, options.mesh);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where(p) + ": " + e.what());
    }
    VoxelizedPart rep;
    rep.name = p.name;
    rep.source = p.source;
    rep.role = p.role;
    rep.label = label;
    rep.voxels = m.insideVoxels;
    rep.voxelVolume = double(m.insideVoxels) * voxelVolume;
    rep.topology = m.topology;
    rep.cutByGrid = m.cutByGrid;
    rep.cavities = m.cavities;
    rep.invertedPieces = m.invertedPieces;
    const std::string at = where(p);
    // A hole wider than about a voxel lets OpenVDB's outside flood fill in: the inside collapses to a
    // few stray voxels, far below what the surface encloses.
    const double enclosed = m.topology.enclosedVolume;
    const double ratio = enclosed > 0 ? rep.voxelVolume / enclosed : 0.0;
    if (m.boxDims[0] == 0) throw std::invalid_argument(at + ": the surface lies outside the voxel grid");
    if (!m.topology.closed() && (m.insideVoxels == 0 || ratio < 0.5)) {
      std::ostringstream e;
      e << at << ": the surface is not closed enough to have an inside (" << m.topology.boundaryEdges
        << " boundary edges; its holes let the outside in: " << rep.voxelVolume / 1000.0 << " ml inside of about "
        << enclosed / 1000.0 << " ml enclosed)";
      throw std::invalid_argument(e.str());
    }
    if (m.insideVoxels == 0)
      throw std::invalid_argument(at + ": the surface encloses no voxel centre (thinner than a voxel?)");
    if (!m.topology.closed()) {
      std::ostringstream w;
      w << at << ": the surface is not closed (" << m.topology.boundaryEdges << " boundary edges, "
        << m.topology.nonManifoldEdges << " non-manifold edges); its inside was taken from the level set's sign: "
        << rep.voxelVolume / 1000.0 << " ml of about " << enclosed / 1000.0 << " ml enclosed";
      out.warnings.push_back(w.str());
    }
    if (m.topology.closed() && m.insideVoxels > 1000 && (ratio < 0.7 || ratio > 1.4)) {
      std::ostringstream w;
      w << at << ": the inside (" << rep.voxelVolume / 1000.0 << " ml) differs from the volume the surface encloses ("
        << enclosed / 1000.0 << " ml): overlapping or inverted pieces?";
      out.warnings.push_back(w.str());
    }
    if (m.invertedPieces > 0)
      out.warnings.push_back(at + ": " + std::to_string(m.invertedPieces) +
                             " piece(s) face inward but lie outside the others: kept as solids");
    if (m.cutByGrid) out.warnings.push_back(at + ": the surface reaches beyond the voxel grid and is cut by it");

    // Paint: bones over tissues over skin; the first of two bones (or tissues) keeps a shared voxel.
    std::size_t outside = 0;
    std::map<int, std::size_t> overlapWith;
    std::mutex mutex;
    const std::size_t nx = std::size_t(m.boxDims[0]), ny = std::size_t(m.boxDims[1]);
    auto priority = [&](std::int32_t value) {
      if (value <= 0) return 0;
      return int(order[std::size_t(value) - 1]->role == VoxelizeRole::Skin ? 1
                 : order[std::size_t(value) - 1]->role == VoxelizeRole::Tissue ? 2
                                                                               : 3);
    };
    const int mine = p.role == VoxelizeRole::Skin ? 1 : p.role == VoxelizeRole::Tissue ? 2 : 3;
    parallelFor(
        std::size_t(m.boxDims[2]),
        [&](std::size_t k0, std::size_t k1) {
          std::size_t o = 0;
          std::map<int, std::size_t> with;
          for (std::size_t k = k0; k < k1; ++k)
            for (std::size_t j = 0; j < ny; ++j)
              for (std::size_t i = 0; i < nx; ++i) {
                if (!m.inside[(k * ny + j) * nx + i]) continue;
                const int gi = m.boxMin[0] + int(i), gj = m.boxMin[1] + int(j), gk = m.boxMin[2] + int(k);
                if (p.role != VoxelizeRole::Skin && !skinMask.at(gi, gj, gk)) ++o;
                std::int32_t& v = out.labels.at(gi, gj, gk);
                const int theirs = priority(v);
                if (theirs == mine && mine > 1)
                  ++with[v];
                else if (theirs <= mine)
                  v = label;
              }
          std::lock_guard<std::mutex> lock(mutex);
          outside += o;
          for (auto [l, c] : with) overlapWith[l] += c;
        },
        1);
    if (p.role != VoxelizeRole::Skin) {
      rep.outsideSkinFraction = double(outside) / double(m.insideVoxels);
      if (outside > 0)
        out.warnings.push_back(at + ": " + percent(rep.outsideSkinFraction) + " of " + p.name + " (" +
                               std::to_string(outside) + " voxels) lies outside the skin; kept in the body");
    }
    for (auto [l, c] : overlapWith)
      out.warnings.push_back(at + ": " + p.name + " overlaps " + order[std::size_t(l) - 1]->name + " in " +
                             std::to_string(c) + " voxels; they stay " + order[std::size_t(l) - 1]->name);
    if (p.role == VoxelizeRole::Skin) skinMask = std::move(m);
    out.table.labels.push_back(
        {label, p.name, p.role == VoxelizeRole::Bone ? LabelKind::Bone : LabelKind::Soft});
    out.parts.push_back(rep);
  }
  // Labelled counts of earlier parts may have been painted over by later ones: recount.
  std::vector<std::size_t> counts(order.size() + 1, 0);
  for (std::int32_t v : out.labels.data) ++counts[std::size_t(v)];
  for (auto& rep : out.parts) rep.labelledVoxels = counts[std::size_t(rep.label)];
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace repose
