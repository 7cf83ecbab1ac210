#include "relaxation_neighbourhood.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "fem_checkpoint.h"
#include "parallel_for.h"
#include "signed_svd.h"

namespace repose {
namespace fem {

namespace {

// The strained region goes first only while it is at most this fraction of the free nodes. A pose that
// moves every joint strains most of the body (the CMU walk's first frame: 85 % on medium, where the part
// first takes 49 s in place of 58 s); all of the free nodes is the whole mesh twice (small, 45 degree
// pose: 14.0 s in place of 11.2 s).
constexpr double kStrainedRegionLargestPart = 0.9;

bool touches(const Tets& tets, Eigen::Index t, const std::vector<char>& set) {
  for (int c = 0; c < 4; ++c)
    if (set[std::size_t(tets(t, c))]) return true;
  return false;
}

// The strained tets' free nodes: those of the tets with a free node whose strain, |sigma - 1|^2 +
// lambda / (2 mu) (det F - 1)^2, exceeds the threshold.
std::vector<int> strainedNodes(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<RestTet>& restTets,
                               double lambda, double mu, const Points& posed, double threshold) {
  const std::size_t nT = std::size_t(tets.rows());
  const double volumeWeight = 0.5 * lambda / mu;
  std::vector<char> strainedTet(nT, 0);
  parallelFor(nT, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      if (!hasFreeNode(tets, fixedBone, t)) continue;
      const auto T = tets.row(Eigen::Index(t));
      Mat3 Ds;
      const Vec3 x0 = node(posed, T[0]);
      for (int c = 0; c < 3; ++c) Ds.col(c) = node(posed, T[c + 1]) - x0;
      Mat3 U, V;
      Vec3 s;
      signedSvd(Ds * restTets[t].DmInv, U, s, V);
      const double J = s.prod();
      strainedTet[t] = (s - Vec3::Ones()).squaredNorm() + volumeWeight * (J - 1.0) * (J - 1.0) > threshold;
    }
  }, 1024);
  std::vector<char> strained(std::size_t(posed.rows()), 0);
  for (std::size_t t = 0; t < nT; ++t)
    if (strainedTet[t])
      for (int a = 0; a < 4; ++a) strained[std::size_t(tets(Eigen::Index(t), a))] = 1;
  std::vector<int> centre;
  for (std::size_t v = 0; v < strained.size(); ++v)
    if (strained[v] && fixedBone[v] < 0) centre.push_back(int(v));
  return centre;
}

}  // namespace

// Grown ring by ring over the tets (a few passes over the tet list: no adjacency to build).
std::vector<char> grownNeighbourhood(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<int>& centre,
                                     int rings) {
  auto isFree = [&](int v) { return fixedBone[std::size_t(v)] < 0; };
  std::vector<char> active(fixedBone.size(), 0);
  for (int v : centre) active[std::size_t(v)] = isFree(v);
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> next = active;
    for (Eigen::Index t = 0; t < tets.rows(); ++t)
      if (touches(tets, t, active))
        for (int c = 0; c < 4; ++c)
          if (isFree(tets(t, c))) next[std::size_t(tets(t, c))] = 1;
    active.swap(next);
  }
  return active;
}

namespace {

// The part of the mesh that a set of unknowns touches, as a mesh of its own: the tets touching an
// unknown, their nodes renumbered; the other nodes held.
struct MeshPart {
  std::vector<int> global;  // part node -> mesh node
  Points rest, posed;
  std::vector<int> fixed;
  Tets tets;
};

// Empty (no tets) when no tet touches an unknown or no node of the part is held (a part of the mesh
// that no bone holds, singular on its own).
MeshPart meshPart(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, const Points& posed,
                  const std::vector<char>& active) {
  const Eigen::Index nV = rest.rows(), nT = tets.rows();
  MeshPart part;
  std::vector<int> local(std::size_t(nV), -1);
  std::vector<int>& global = part.global;
  std::vector<Eigen::Index> partTets;
  for (Eigen::Index t = 0; t < nT; ++t)
    if (touches(tets, t, active)) {
      partTets.push_back(t);
      for (int c = 0; c < 4; ++c) {
        const int v = tets(t, c);
        if (local[std::size_t(v)] < 0) {
          local[std::size_t(v)] = int(global.size());
          global.push_back(v);
        }
      }
    }
  if (partTets.empty() || std::none_of(global.begin(), global.end(), [&](int v) { return !active[std::size_t(v)]; }))
    return MeshPart{};
  const Eigen::Index m = Eigen::Index(global.size());
  part.rest.resize(m, 3);
  part.posed.resize(m, 3);
  part.fixed.resize(static_cast<std::size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k) {
    const int v = global[std::size_t(k)];
    part.rest.row(k) = rest.row(v);
    part.posed.row(k) = posed.row(v);
    // Held nodes keep their bone (or 0 for a held free node: the id only matters to the continuation).
    part.fixed[std::size_t(k)] = active[std::size_t(v)] ? -1 : std::max(0, fixedBone[std::size_t(v)]);
  }
  part.tets.resize(Eigen::Index(partTets.size()), 4);
  for (std::size_t q = 0; q < partTets.size(); ++q)
    for (int c = 0; c < 4; ++c) part.tets(Eigen::Index(q), c) = local[std::size_t(tets(partTets[q], c))];
  return part;
}

// The part's solve: the whole solve's model, solver and tolerances, none of its extra stages; its
// checkpoint reports `phase`.
CorotationalOptions partOptions(const CorotationalOptions& options, RelaxationProgress::Phase phase) {
  CorotationalOptions o = options;
  o.volumeRegions.clear();
  o.pathVolumeRegions.clear();
  o.boneParents.clear();
  o.startCorrection.resize(0, 3);
  o.continuation = CorotationalOptions::Never;
  o.untangle = false;
  o.strainedRegionThreshold = 0.0;
  if (options.checkpoint)
    o.checkpoint = [&options, phase](const RelaxationProgress& p) {
      RelaxationProgress part = p;
      part.phase = phase;
      return options.checkpoint(part);
    };
  return o;
}

}  // namespace

int relaxPart(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
              const std::vector<char>& active, const CorotationalOptions& options, RelaxationProgress::Phase phase,
              CorotationalReport* report) {
  MeshPart part = meshPart(rest, tets, fixedBone, posed, active);
  if (part.tets.rows() == 0) {
    if (report) *report = CorotationalReport{};
    return 0;
  }
  relaxCorotational(part.rest, part.tets, part.fixed, part.posed, partOptions(options, phase), report);
  int unknowns = 0;
  for (Eigen::Index k = 0; k < part.posed.rows(); ++k)
    if (part.fixed[std::size_t(k)] < 0) {
      posed.row(part.global[std::size_t(k)]) = part.posed.row(k);
      ++unknowns;
    }
  return unknowns;
}

bool relaxStrainedRegionFirst(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                              const std::vector<RestTet>& restTets, std::size_t nFree, double lambda, double mu,
                              Points& posed, const CorotationalOptions& options, CorotationalReport& rep) {
  const auto regionStart = std::chrono::steady_clock::now();
  const std::vector<int> centre =
      strainedNodes(tets, fixedBone, restTets, lambda, mu, posed, options.strainedRegionThreshold);
  const std::vector<char> unknown = grownNeighbourhood(tets, fixedBone, centre, options.strainedRegionRings);
  const std::size_t partNodes = std::size_t(std::count(unknown.begin(), unknown.end(), char(1)));
  // A part of most of the mesh costs what the whole does (and a pose strained all over is no
  // skinned one: a fold from a bad start, say), so then the whole mesh goes at once.
  bool ran = false;
  if (partNodes > 0 && partNodes <= kStrainedRegionLargestPart * double(nFree)) {
    CorotationalReport part;
    try {
      rep.strainedRegionNodes = relaxPart(rest, tets, fixedBone, posed, unknown, options,
                                          RelaxationProgress::StrainedRegion, &part);
      ran = rep.strainedRegionNodes > 0;
    } catch (const RelaxationCancelled&) {
      throw;
    } catch (const std::runtime_error&) {
      // A part singular on its own (see the untangling's neighbourhoods): the whole mesh from posed.
    }
    rep.strainedRegionNewtonIterations = part.newtonIterations;
  }
  rep.strainedRegionSeconds = seconds(regionStart);
  return ran;
}

}  // namespace fem

void relaxNeighbourhood(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                        const std::vector<int>& centre, int rings, const CorotationalOptions& options,
                        CorotationalReport* report) {
  const Eigen::Index nV = rest.rows(), nT = tets.rows();
  if (posed.rows() != nV || Eigen::Index(fixedBone.size()) != nV)
    throw std::invalid_argument("relaxNeighbourhood: rest, posed and fixedBone differ in size");
  if (nT > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= nV))
    throw std::invalid_argument("relaxNeighbourhood: a tet has a node index outside [0, " + std::to_string(nV) + ")");
  for (int v : centre)
    if (v < 0 || v >= nV) throw std::invalid_argument("relaxNeighbourhood: centre node " + std::to_string(v) + " out of range");
  fem::relaxPart(rest, tets, fixedBone, posed, fem::grownNeighbourhood(tets, fixedBone, centre, rings), options,
                 RelaxationProgress::Neighbourhood, report);
}

}  // namespace repose
