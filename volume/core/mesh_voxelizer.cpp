#include "mesh_voxelizer.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "parallel_for.h"
#include "winding_inside.h"
#include "winding_number.h"

namespace repose {
namespace {

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

/// A volume for people: "3.86 ml", "460.1 ml", "79.29 L".
std::string volumeText(double mm3) {
  std::ostringstream s;
  s << std::fixed;
  if (mm3 >= 1e6)
    s << std::setprecision(2) << mm3 / 1e6 << " L";
  else
    s << std::setprecision(mm3 < 1e4 ? 2 : 1) << mm3 / 1000.0 << " ml";
  return s.str();
}

/// Signed volume of each piece (about the piece's own centroid): positive when it faces outward.
std::vector<double> pieceVolumes(const MeshVertices& V, const MeshTriangles& F, const std::vector<int>& piece,
                                 std::size_t pieces) {
  std::vector<Eigen::Vector3d> centroid(pieces, Eigen::Vector3d::Zero());
  std::vector<double> corners(pieces, 0), six(pieces, 0);
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c) centroid[std::size_t(piece[std::size_t(t)])] += V.row(F(t, c)).transpose();
  for (Eigen::Index t = 0; t < F.rows(); ++t) corners[std::size_t(piece[std::size_t(t)])] += 3;
  for (std::size_t p = 0; p < pieces; ++p) centroid[p] /= std::max(1.0, corners[p]);
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const Eigen::Vector3d& c = centroid[std::size_t(piece[std::size_t(t)])];
    const Eigen::Vector3d a = V.row(F(t, 0)).transpose() - c, b = V.row(F(t, 1)).transpose() - c,
                          d = V.row(F(t, 2)).transpose() - c;
    six[std::size_t(piece[std::size_t(t)])] += a.dot(b.cross(d));
  }
  for (double& x : six) x /= 6.0;
  return six;
}

/// The soup's triangles oriented so that the winding number counts the inside (see voxelizeMesh).
struct OrientedSoup {
  MeshTriangles F;
  OrientationRepairs repairs;
};

void flip(MeshTriangles& F, Eigen::Index t) { std::swap(F(t, 1), F(t, 2)); }

/// Whether each listed inward piece lies inside the other pieces (a cavity) rather than beside them:
/// the others' winding number, w of the whole soup minus the piece's own (exact) part, is at least
/// 1/2 at most of its vertices (16 sampled).
std::vector<bool> insideOthers(const MeshVertices& V, const MeshTriangles& F, const std::vector<int>& piece,
                               const std::vector<std::size_t>& inward) {
  const WindingNumberTree tree(V, F);
  std::vector<std::vector<Eigen::Index>> trianglesOf(*std::max_element(inward.begin(), inward.end()) + 1);
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const std::size_t p = std::size_t(piece[std::size_t(t)]);
    if (p < trianglesOf.size()) trianglesOf[p].push_back(t);
  }
  std::vector<bool> cavity;
  for (std::size_t p : inward) {
    const std::vector<Eigen::Index>& tris = trianglesOf[p];
    MeshTriangles own(Eigen::Index(tris.size()), 3);
    for (std::size_t n = 0; n < tris.size(); ++n) own.row(Eigen::Index(n)) = F.row(tris[n]);
    const std::size_t samples = std::min<std::size_t>(16, tris.size()), step = tris.size() / samples;
    std::size_t enclosed = 0;
    for (std::size_t n = 0; n < samples; ++n) {
      const Eigen::Vector3d q = V.row(own(Eigen::Index(n * step), 0)).transpose();
      enclosed += tree(q) - windingNumberExact(V, own, q) >= 0.5;
    }
    cavity.push_back(2 * enclosed > samples);
  }
  return cavity;
}

OrientedSoup orientPieces(const MeshVertices& V, const MeshTriangles& mixed) {
  OrientedSoup out;
  out.F = consistentlyOriented(V, mixed, out.repairs.trianglesTurned);
  std::size_t pieces = 0;
  const std::vector<int> piece = meshPieces(V, out.F, pieces);
  std::vector<double> volume = pieceVolumes(V, out.F, piece, pieces);
  auto smaller = [](double a, double b) { return std::abs(a) < std::abs(b); };
  const std::size_t largest = std::size_t(std::max_element(volume.begin(), volume.end(), smaller) - volume.begin());
  if (volume[largest] < 0) {
    out.repairs.turnedOutward = true;
    for (Eigen::Index t = 0; t < out.F.rows(); ++t) flip(out.F, t);
    for (double& v : volume) v = -v;
  }
  std::vector<std::size_t> inward;
  for (std::size_t p = 0; p < pieces; ++p)
    if (volume[p] < 0) inward.push_back(p);
  if (inward.empty()) return out;
  const std::vector<bool> cavity = insideOthers(V, out.F, piece, inward);
  std::vector<bool> turn(pieces, false);
  for (std::size_t n = 0; n < inward.size(); ++n) {
    turn[inward[n]] = !cavity[n];
    (cavity[n] ? out.repairs.cavities : out.repairs.invertedPieces) += 1;
  }
  for (Eigen::Index t = 0; t < out.F.rows(); ++t)
    if (turn[std::size_t(piece[std::size_t(t)])]) flip(out.F, t);
  return out;
}

}  // namespace

MeshVoxelization voxelizeMesh(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                              const MeshVoxelizeOptions& options) {
  checkGrid(grid);
  checkMesh(V, F);
  MeshVoxelization r;
  r.topology = analyzeMeshTopology(V, F);  // also checks the indices
  const OrientedSoup soup = orientPieces(V, F);
  r.repairs = soup.repairs;
  WindingInsideOptions o;
  o.holeReach = options.holeReach;
  static_cast<WindingInside&>(r) = insideByWindingNumber(V, soup.F, grid, o);
  if (options.findHollows) r.hollows = fillEnclosedHollows(V, soup.F, grid, r, options.hollows);
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
      << " mm) needs " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << " = " << std::setprecision(4) << count
      << " voxels, above the limit of " << maxVoxels << "; use a voxel size of at least about " << fit
      << " mm or raise the limit";
    throw std::invalid_argument(s.str());
  }
  return g;
}

namespace {

/// What was put right in a part, or "closed".
std::string repairs(const VoxelizedPart& p) {
  const MeshTopology& t = p.topology;
  std::ostringstream s;
  s << std::fixed;
  if (t.holes > 0)
    s << t.holes << " hole(s) spanned (" << t.boundaryEdges << " boundary edges, the largest " << std::setprecision(1)
      << t.largestHole << " mm across; mean winding number inside " << std::setprecision(2) << p.meanInsideWinding
      << "), ";
  if (t.pieces > 1) {
    s << t.pieces << " pieces";
    if (p.overlapVolume > 0) s << " overlapping in " << volumeText(p.overlapVolume) << ", united";
    s << ", ";
  }
  if (t.pieces <= 1 && p.overlapVolume > 0)
    s << "folded over itself in " << volumeText(p.overlapVolume) << ", counted once, ";
  if (t.nonManifoldEdges > 0) s << t.nonManifoldEdges << " non-manifold edges, ";
  const OrientationRepairs& o = p.repairs;
  if (o.trianglesTurned > 0) s << o.trianglesTurned << " triangles turned to agree with their neighbours, ";
  if (o.turnedOutward) s << "turned outward (it faced inward), ";
  if (o.cavities > 0) s << o.cavities << " cavities carved, ";
  if (o.invertedPieces > 0) s << o.invertedPieces << " inward pieces turned outward, ";
  std::string out = s.str();
  if (out.empty()) return "closed";
  return out.substr(0, out.size() - 2);
}

/// What a bone's hollows became, or "" when it has none.
std::string hollowsText(const EnclosedHollows& h, double voxelVolume) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  std::size_t thin = 0;
  for (const auto& x : h.hollows) thin += x.thin;
  if (thin > 0)
    s << (h.filled ? "filled " : "left open ") << volumeText(double(h.thinVoxels) * voxelVolume)
      << " of hollow interior (" << thin << (thin == 1 ? " hollow" : " hollows") << ", radius up to "
      << h.largestThinRadiusMm << " mm), ";
  if (thin < h.hollows.size())
    s << "kept " << h.hollows.size() - thin << (h.hollows.size() - thin == 1 ? " cavity" : " cavities") << " of "
      << volumeText(double(h.wideVoxels) * voxelVolume) << " (radius " << h.smallestWideRadiusMm
      << " mm or more: room for an organ), ";
  std::string out = s.str();
  return out.empty() ? out : out.substr(0, out.size() - 2);
}

}  // namespace

std::string LabelVoxelization::text() const {
  std::ostringstream s;
  const auto& g = labels.grid;
  s << "grid " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << " voxels of " << g.spacing.x() << " x "
    << g.spacing.y() << " x " << g.spacing.z() << " mm, origin (" << g.origin.x() << ", " << g.origin.y() << ", "
    << g.origin.z() << ")\n";
  const double voxelVolume = g.spacing.prod();
  for (const auto& p : parts) {
    const bool bone = p.role == VoxelizeRole::Bone;
    const std::string hollows = bone ? hollowsText(p.hollows, voxelVolume) : "";
    s << "  " << p.label << " " << p.name << " (" << roleName(p.role) << ", " << (p.source.empty() ? p.name : p.source)
      << "): " << p.topology.triangles << " triangles, " << repairs(p) << (hollows.empty() ? "" : "; " + hollows)
      << ": " << (bone ? "shell " : "") << p.voxels << " voxels, " << volumeText(p.voxelVolume) << " (the mesh encloses "
      << (p.topology.holes > 0 ? "about " : "") << volumeText(p.topology.enclosedVolume) << ")";
    if (bone) s << ", solid " << p.solidVoxels << " voxels, " << volumeText(p.solidVolume);
    s << "; " << std::fixed << std::setprecision(2) << p.seconds << " s\n" << std::defaultfloat;
  }
  for (const auto& w : warnings) s << "warning: " << w << "\n";
  return s.str();
}

namespace {

/// The part's report from its voxelization; throws when it has no inside worth the name, adds warnings.
VoxelizedPart judge(const VoxelizePart& p, const MeshVoxelization& m, double voxelVolume,
                    std::vector<std::string>& warnings) {
  VoxelizedPart rep;
  rep.name = p.name;
  rep.source = p.source;
  rep.role = p.role;
  rep.voxels = m.insideVoxels;
  rep.voxelVolume = double(m.insideVoxels) * voxelVolume;
  rep.hollows = m.hollows;
  rep.solidVoxels = m.insideVoxels + (p.role == VoxelizeRole::Bone ? m.hollows.thinVoxels : 0);
  rep.solidVolume = double(rep.solidVoxels) * voxelVolume;
  rep.overlapVolume = double(m.overlapVoxels) * voxelVolume;
  rep.meanInsideWinding = m.meanInsideWinding;
  rep.topology = m.topology;
  rep.cutByGrid = m.cutByGrid;
  rep.repairs = m.repairs;
  const std::string at = where(p);
  const MeshTopology& t = m.topology;
  if (m.outsideGrid) throw std::invalid_argument(at + ": the surface lies outside the voxel grid");
  if (t.boundaryEdges > 0 && (m.insideVoxels == 0 || m.meanInsideWinding < kMinInsideWinding)) {
    std::ostringstream e;
    e << std::fixed << at << ": the surface is not closed enough to have an inside (" << t.holes << " hole(s), "
      << t.boundaryEdges << " boundary edges, the largest hole " << std::setprecision(1) << t.largestHole
      << " mm across): ";
    if (m.insideVoxels == 0)
      e << "nothing has a winding number of 1/2 or more";
    else
      e << "its winding number inside averages " << std::setprecision(2) << m.meanInsideWinding
        << " where a closed surface has 1";
    e << "; close the holes or give a closed surface";
    throw std::invalid_argument(e.str());
  }
  if (m.insideVoxels == 0)
    throw std::invalid_argument(at + ": the surface encloses no voxel centre (thinner than a voxel?)");
  const double ratio = t.enclosedVolume > 0 ? (rep.voxelVolume + rep.overlapVolume) / t.enclosedVolume : 0.0;
  if (t.closed() && m.repairs.cavities == 0 && m.insideVoxels > 1000 && (ratio < 0.7 || ratio > 1.4))
    warnings.push_back(at + ": the inside (" + volumeText(rep.voxelVolume) +
                       ") differs from the volume the surface encloses (" + volumeText(t.enclosedVolume) +
                       "): thinner than a few voxels?");
  if (m.repairs.invertedPieces > 0)
    warnings.push_back(at + ": " + std::to_string(m.repairs.invertedPieces) +
                       " piece(s) face inward but lie outside the others: turned outward, kept as solids");
  if (m.cutByGrid) warnings.push_back(at + ": the surface reaches beyond the voxel grid and is cut by it");
  return rep;
}

}  // namespace

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
      checkTriangleIndices(p.V, p.F);
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
    const auto started = std::chrono::steady_clock::now();
    MeshVoxelizeOptions meshOptions = options.mesh;
    if (p.role == VoxelizeRole::Bone) {
      meshOptions.findHollows = true;
      meshOptions.hollows.fill = !options.hollowBones;
      meshOptions.hollows.maxFillRadiusMm = options.maxMarrowRadiusMm;
    }
    try {
      m = voxelizeMesh(p.V, p.F, grid, meshOptions);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where(p) + ": " + e.what());
    }
    VoxelizedPart rep = judge(p, m, voxelVolume, out.warnings);
    rep.label = label;
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const std::string at = where(p);

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
      const std::size_t painted = m.insideVoxels + (m.hollows.filled ? m.hollows.thinVoxels : 0);
      rep.outsideSkinFraction = double(outside) / double(painted);
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
