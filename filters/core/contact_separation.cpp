#include "contact_separation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "distance_transform.h"
#include "nearest_bones.h"
#include "parallel_for.h"

namespace repose {

namespace {

using Pair = std::pair<int, int>;  // bone indices, first < second

// A gap between two parts up to this many times the crease's reach still faces the other part.
constexpr int kGapReach = 3;
// The boundary between a bone and its parent is kept within this many times the child joint's
// depth (distance from its centre to the outside) of the centre: the joint's own tissue.
constexpr double kJointGuard = 1.5;
// Free skin must be this many voxels nearer than the crease to keep a boundary voxel.
constexpr double kMargin = 1.0;
// Largest shift (mm) of a contact's boundary toward one part: where two parts truly meet, it is the
// difference of their depths over their bones (a hand on a thigh: about 35 mm).
constexpr double kMaxShiftMm = 60.0;
// |cos| of the angle between a line across a slit and the axis of a child bone lying against its
// parent, at most: 0.5 = within 30 degrees of square to it.
constexpr double kAcrossAxis = 0.5;

// Unit axis of each bone: from its joint centre to the centroid of its voxels (bone map); zero for a
// bone without voxels or centred on its joint.
std::vector<Eigen::Vector3d> boneAxes(const Volume<std::int16_t>& bone, const Skeleton& skeleton) {
  const ImageGrid& g = bone.grid;
  std::vector<Eigen::Vector3d> sum(skeleton.size(), Eigen::Vector3d::Zero());
  std::vector<double> count(skeleton.size(), 0);
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const int b = bone.at(i, j, k);
        if (b < 0 || b >= int(skeleton.size())) continue;
        sum[b] += g.indexToPhysical(Eigen::Vector3d(i, j, k));
        ++count[b];
      }
  std::vector<Eigen::Vector3d> axes(skeleton.size(), Eigen::Vector3d::Zero());
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    if (count[b] == 0) continue;
    const Eigen::Vector3d a = sum[b] / count[b] - skeleton.joints[b].center;
    if (a.norm() > 1e-6) axes[b] = a.normalized();
  }
  return axes;
}
Pair makePair(int a, int b) { return a < b ? Pair{a, b} : Pair{b, a}; }

struct Neighbourhood {
  const ImageGrid& g;
  std::vector<std::array<int, 3>> offsets;
  std::vector<float> mm;
  explicit Neighbourhood(const ImageGrid& grid) : g(grid) {
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
          if (di || dj || dk) {
            offsets.push_back({di, dj, dk});
            mm.push_back(float(std::sqrt(std::pow(di * g.spacing[0], 2) + std::pow(dj * g.spacing[1], 2) +
                                         std::pow(dk * g.spacing[2], 2))));
          }
  }
  /// Calls f(neighbour index, step mm) for the 26 neighbours of v inside the grid.
  template <class F>
  void forEach(std::size_t v, F&& f) const {
    const int nx = g.dims[0], ny = g.dims[1];
    const int i = int(v % nx), j = int((v / nx) % ny), k = int(v / (std::size_t(nx) * ny));
    for (std::size_t s = 0; s < offsets.size(); ++s) {
      const int a = i + offsets[s][0], b = j + offsets[s][1], c = k + offsets[s][2];
      if (g.contains(a, b, c)) f(g.linearIndex(a, b, c), mm[s]);
    }
  }
};

// Calls f(w1, w2, step) for each line through background voxel v (13 directions, `step` in voxel
// index units) that meets the body on both sides within `reach` steps, with the first body voxel
// met on each side; stops when f returns true. Returns whether any line did.
template <class F>
bool sandwichSides(const MaskVolume& body, std::size_t v, int reach, F&& f) {
  const ImageGrid& g = body.grid;
  const int nx = g.dims[0], ny = g.dims[1];
  const int i = int(v % nx), j = int((v / nx) % ny), k = int(v / (std::size_t(nx) * ny));
  auto hit = [&](int di, int dj, int dk) -> std::ptrdiff_t {
    for (int t = 1; t <= reach; ++t) {
      const int a = i + t * di, b = j + t * dj, c = k + t * dk;
      if (!g.contains(a, b, c)) return -1;
      if (body.at(a, b, c)) return std::ptrdiff_t(g.linearIndex(a, b, c));
    }
    return -1;
  };
  bool any = false;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int first = di ? di : dj ? dj : dk;  // one of each opposite pair
        if (first <= 0) continue;
        const std::ptrdiff_t w1 = hit(di, dj, dk);
        if (w1 < 0) continue;
        const std::ptrdiff_t w2 = hit(-di, -dj, -dk);
        if (w2 < 0) continue;
        any = true;
        if (f(std::size_t(w1), std::size_t(w2), Eigen::Vector3d(di, dj, dk))) return true;
      }
  return any;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The pelvis and the segments of the spinal column are one trunk: a crease between a segment and
// the next (a belly over the pubis, rolls of the back) is the trunk folding, never a contact. The
// head and the limbs are not of it (a chin on the chest, an arm against the torso are contacts).
bool spinalSegment(const std::string& name) {
  return name == "pelvis" || name == "spine" || name.rfind("vertebra_", 0) == 0;
}

bool trunkFold(const Skeleton& skeleton, int a, int b) {
  const Joint& ja = skeleton.joints[std::size_t(a)];
  const Joint& jb = skeleton.joints[std::size_t(b)];
  return (ja.parent == b || jb.parent == a) && spinalSegment(ja.name) && spinalSegment(jb.name);
}

}  // namespace

std::string ContactSeparationReport::text(const Skeleton& skeleton) const {
  std::ostringstream out;
  auto name = [&](int b) {
    return b >= 0 && b < int(skeleton.size()) ? skeleton.joints[b].name : "bone " + std::to_string(b);
  };
  for (const Contact& c : contacts)
    out << "contact " << name(c.boneA) << " | " << name(c.boneB) << ": " << c.voxelsCut << " voxels cut ("
        << std::lround(c.areaMm2 / 100) << " cm2), boundary moved " << std::lround(c.offsetMm) << " mm\n";
  return out.str();
}

namespace {

// Crease analysis of the scan's body: 1 for background in a slit (sandwiched between body voxels)
// and deep in it, 2 for other background beside the body (free skin), 0 elsewhere.
std::vector<std::uint8_t> creaseMap(const MaskVolume& body, const Neighbourhood& nbh,
                                    const ContactSeparationOptions& options) {
  const ImageGrid& g = body.grid;
  const std::size_t n = g.voxelCount();
  MaskVolume openAir;  // background that is not sandwiched
  openAir.grid = g;
  openAir.data.assign(n, 0);
  std::vector<std::uint8_t> crease(n, 0);
  parallelFor(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (body.data[v]) continue;
      const bool inSlit = sandwichSides(body, v, options.creaseReach,
                                        [](std::size_t, std::size_t, const Eigen::Vector3d&) { return true; });
      openAir.data[v] = inSlit ? 0 : 1;
      bool beside = false;
      nbh.forEach(v, [&](std::size_t w, float) { beside = beside || body.data[w]; });
      if (beside) crease[v] = inSlit ? 1 : 2;
    }
  }, 4096);
  const std::vector<float> toOpenAir = distanceToFeatures(openAir);
  const double minDepth = options.creaseDepthMm > 0 ? options.creaseDepthMm : 1.5 * g.spacing.mean();
  for (std::size_t v = 0; v < n; ++v)
    if (crease[v] == 1 && toOpenAir[v] < minDepth) crease[v] = 2;
  return crease;
}

// One pass of separateContacts on `body` (cut in place): segments from the body as it is, creases
// and the sides of each crease from the scan's body.
// One pass of the contact cut: the stages below share the scan's maps, the nearest bones and the
// segments, and each reads as the step of the method it is.
struct ContactCutPass {
  MaskVolume& body;
  const MaskVolume& scanBody;
  const std::vector<std::uint8_t>& crease;
  const Volume<std::int16_t>& bone;
  const Skeleton& skeleton;
  const ContactSeparationOptions& options;
  const Neighbourhood& nbh;
  const ImageGrid& g = body.grid;
  const std::size_t n = g.voxelCount();
  // Segments: the nearest bone of every body voxel, then moved at each contact.
  const NearestBones nb = nearestBones(body, bone);
  std::vector<std::int16_t> seg = nb.first;
  std::map<Pair, std::size_t> contactIndex{};  // the pair's contact in report.contacts
  ContactSeparationReport report{};

  ContactSeparationReport run();
  void findContacts();
  void shiftBoundaries();
  void reattachDetachedTissue();
  std::vector<std::int32_t> creasesBetweenParts();
  std::vector<std::vector<std::size_t>> contactBoundaries() const;
  std::vector<float> depthInBody() const;
  bool guarded(const Pair& p, std::size_t v, const std::vector<float>& depth) const;
  struct Seeds {
    std::vector<std::size_t> crease, skin;
  };
  Seeds sheetSeeds(std::size_t c, const Pair& p, const std::vector<std::size_t>& sheet,
                   const std::vector<std::int32_t>& creaseContact) const;
  std::vector<float> alongSheet(const std::vector<std::size_t>& sheet,
                                const std::unordered_map<std::size_t, std::size_t>& slot,
                                const std::vector<std::size_t>& seeds) const;
  void cutSheet(std::size_t c, const std::vector<std::size_t>& sheet, const std::vector<std::int32_t>& creaseContact,
                const std::vector<float>& depth, const std::vector<std::size_t>& segmentVoxels,
                std::vector<std::pair<std::size_t, std::size_t>>& cut) const;
};

ContactSeparationReport ContactCutPass::run() {
  findContacts();
  if (report.contacts.empty()) return report;
  shiftBoundaries();
  reattachDetachedTissue();
  const std::vector<std::int32_t> creaseContact = creasesBetweenParts();
  const std::vector<std::vector<std::size_t>> boundaryOf = contactBoundaries();
  const std::vector<float> depth = depthInBody();
  // Which boundary voxels are the contact: those nearer (along the boundary) to where it meets the
  // outside in a crease between the two parts than to where it meets free skin, by a margin that
  // keeps the rim's voxel noise (a slit only partly seen as a crease) from cutting it into patches;
  // not those at the joint between a bone and its parent.
  std::vector<std::pair<std::size_t, std::size_t>> cut;  // voxel, contact
  std::vector<std::size_t> segmentVoxels(skeleton.size() + 1, 0);
  for (std::size_t v = 0; v < n; ++v)
    if (body.data[v] && seg[v] >= 0 && std::size_t(seg[v]) < skeleton.size()) ++segmentVoxels[seg[v]];
  for (std::size_t c = 0; c < report.contacts.size(); ++c)
    cutSheet(c, boundaryOf[c], creaseContact, depth, segmentVoxels, cut);
  std::sort(cut.begin(), cut.end());
  cut.erase(std::unique(cut.begin(), cut.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
            cut.end());
  const double faceArea = g.spacing.prod() / (g.spacing.sum() / 3);
  for (const auto& [v, contact] : cut) {
    ContactSeparationReport::Contact& c = report.contacts[contact];
    ++c.voxelsCut;
    c.areaMm2 += faceArea;
    body.data[v] = 0;
  }
  report.voxelsCut = cut.size();
  // Pairs whose creases turned out to lie between other parts, or that needed no cut, are no contacts.
  report.contacts.erase(std::remove_if(report.contacts.begin(), report.contacts.end(),
                                       [](const ContactSeparationReport::Contact& c) { return c.voxelsCut == 0; }),
                        report.contacts.end());
  return report;
}

void ContactCutPass::findContacts() {
  // Contacts: the parts on the two sides of each crease voxel, and how much nearer the one's bone is
  // than the other's there: their boundary must pass through the crease. A side's part is its
  // nearest bone; where both sides have the same (a thin part whose tissue is nearer to the thick
  // part's bone), the other is the second nearest bone of the side where it is nearer.
  std::map<Pair, std::vector<std::size_t>> creaseOf;
  std::map<Pair, std::vector<double>> shiftSamples;  // dA - dB (A the pair's first) at the crease
  for (std::size_t v = 0; v < n; ++v) {
    if (crease[v] != 1) continue;
    sandwichSides(body, v, options.creaseReach, [&](std::size_t w1, std::size_t w2, const Eigen::Vector3d&) {
      int a = nb.first[w1], b = nb.first[w2];
      if (a < 0 || b < 0) return false;
      if (a == b) {
        const std::size_t w = nb.secondMm[w1] <= nb.secondMm[w2] ? w1 : w2;
        if (nb.second[w] < 0) return false;
        b = nb.second[w];
      }
      const Pair p = makePair(a, b);
      // Distances from v to the two bones, through the tissue beside it.
      double dA = std::numeric_limits<double>::infinity(), dB = dA;
      nbh.forEach(v, [&](std::size_t w, float mm) {
        if (!body.data[w]) return;
        for (int q = 0; q < 2; ++q) {
          const int bone = q ? nb.second[w] : nb.first[w];
          const double d = (q ? nb.secondMm[w] : nb.firstMm[w]) + mm;
          if (bone == p.first) dA = std::min(dA, d);
          if (bone == p.second) dB = std::min(dB, d);
        }
      });
      if (!std::isfinite(dA) || !std::isfinite(dB)) return false;
      creaseOf[p].push_back(v);
      shiftSamples[p].push_back(dA - dB);
      return true;
    });
  }
  for (auto& [p, voxels] : creaseOf) {
    if (voxels.size() < options.minCreaseVoxels) continue;
    ContactSeparationReport::Contact c;
    c.boneA = p.first, c.boneB = p.second;
    c.creaseVoxels = voxels.size();
    c.offsetMm = median(shiftSamples[p]);
    // A crease far nearer to one bone than the other lies inside that bone's part (a fold of it),
    // not where the two parts meet.
    if (std::abs(c.offsetMm) > kMaxShiftMm) continue;
    if (trunkFold(skeleton, p.first, p.second)) continue;
    contactIndex[p] = report.contacts.size();
    report.contacts.push_back(c);
  }
}

void ContactCutPass::shiftBoundaries() {
  // Move each contact's boundary to pass through its crease: where A and B are a voxel's two
  // nearest bones, it joins A when dA - dB is below the shift.
  parallelFor(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (!body.data[v] || bone.data[v] >= 0 || nb.second[v] < 0) continue;
      const auto it = contactIndex.find(makePair(nb.first[v], nb.second[v]));
      if (it == contactIndex.end()) continue;
      const ContactSeparationReport::Contact& c = report.contacts[it->second];
      const double dA = nb.first[v] == c.boneA ? nb.firstMm[v] : nb.secondMm[v];
      const double dB = nb.first[v] == c.boneA ? nb.secondMm[v] : nb.firstMm[v];
      seg[v] = std::int16_t(dA - dB < c.offsetMm ? c.boneA : c.boneB);
    }
  }, 4096);
}

void ContactCutPass::reattachDetachedTissue() {
  // A segment is one piece holding its bone: what the shift detached from it (tissue of the other
  // part across a gap) goes back to its nearest bone.
  {
    std::vector<std::uint8_t> reached(n, 0);
    std::vector<std::size_t> stack;
    for (std::size_t v = 0; v < n; ++v)
      if (body.data[v] && bone.data[v] >= 0 && bone.data[v] == seg[v]) reached[v] = 1, stack.push_back(v);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      nbh.forEach(v, [&](std::size_t w, float) {
        if (!reached[w] && body.data[w] && seg[w] == seg[v]) reached[w] = 1, stack.push_back(w);
      });
    }
    for (std::size_t v = 0; v < n; ++v)
      if (body.data[v] && !reached[v]) seg[v] = nb.first[v];
  }
}

std::vector<std::int32_t> ContactCutPass::creasesBetweenParts() {
  // A crease lies between two parts when the voxels sandwiching it are of two segments: the slit
  // between two knees is a contact of the knees, not of a femur and its own tibia beside it. A bone
  // lies against its parent along its length (an arm against the torso, a forearm folded on the
  // upper arm), so there the line across the slit must be within 30 degrees of square to the
  // child's axis; a fold across it (a belly over the pubis, a gluteal fold) is the tissue folding,
  // no contact.
  const std::vector<Eigen::Vector3d> axes = boneAxes(bone, skeleton);
  std::vector<std::int32_t> creaseContact(n, -1);
  std::vector<std::size_t> creasesBetween(report.contacts.size(), 0);
  for (std::size_t v = 0; v < n; ++v) {
    if (crease[v] != 1) continue;
    sandwichSides(scanBody, v, options.creaseReach, [&](std::size_t w1, std::size_t w2, const Eigen::Vector3d& step) {
      if (!body.data[w1] || !body.data[w2] || seg[w1] < 0 || seg[w2] < 0 || seg[w1] == seg[w2]) return false;
      const auto it = contactIndex.find(makePair(seg[w1], seg[w2]));
      if (it == contactIndex.end()) return false;
      for (int child : {int(seg[w1]), int(seg[w2])}) {
        const int parent = skeleton.joints[child].parent;
        if (parent != seg[w1] && parent != seg[w2]) continue;
        const Eigen::Vector3d across = (g.direction * step.cwiseProduct(g.spacing)).normalized();
        if (std::abs(across.dot(axes[child])) > kAcrossAxis) return false;
      }
      creaseContact[v] = std::int32_t(it->second);
      ++creasesBetween[it->second];
      return true;
    });
  }
  for (std::size_t c = 0; c < report.contacts.size(); ++c) {
    report.contacts[c].creaseVoxels = creasesBetween[c];
    if (creasesBetween[c] < options.minCreaseVoxels) report.contacts[c].creaseVoxels = 0;
  }
  return creaseContact;
}

std::vector<std::vector<std::size_t>> ContactCutPass::contactBoundaries() const {
  // Each contact's boundary: the voxels of either segment with a 26-neighbour in the other (a voxel
  // where three segments meet lies on two boundaries).
  std::vector<std::vector<std::size_t>> boundaryOf(report.contacts.size());
  for (std::size_t v = 0; v < n; ++v) {
    if (!body.data[v] || seg[v] < 0) continue;
    std::array<std::int16_t, 8> others{};
    int nOthers = 0;
    nbh.forEach(v, [&](std::size_t w, float) {
      if (!body.data[w] || seg[w] < 0 || seg[w] == seg[v] || nOthers == int(others.size())) return;
      if (std::find(others.begin(), others.begin() + nOthers, seg[w]) == others.begin() + nOthers)
        others[nOthers++] = seg[w];
    });
    for (int o = 0; o < nOthers; ++o) {
      const auto it = contactIndex.find(makePair(seg[v], others[o]));
      if (it != contactIndex.end() && report.contacts[it->second].creaseVoxels > 0) boundaryOf[it->second].push_back(v);
    }
  }
  return boundaryOf;
}

// Each body voxel's distance (mm) to the outside.
std::vector<float> ContactCutPass::depthInBody() const {
  MaskVolume outside;
  outside.grid = g;
  outside.data.resize(n);
  for (std::size_t v = 0; v < n; ++v) outside.data[v] = body.data[v] ? 0 : 1;
  return distanceToFeatures(outside);
}

// Joint guard: a boundary between a bone and its parent stays within the child's depth of its centre.
bool ContactCutPass::guarded(const Pair& p, std::size_t v, const std::vector<float>& depth) const {
  for (int child : {p.first, p.second}) {
    const int parent = skeleton.joints[child].parent;
    if (parent != p.first && parent != p.second) continue;
    const Eigen::Vector3d ijk = g.physicalToIndex(skeleton.joints[child].center).array().round();
    if (!g.contains(int(ijk[0]), int(ijk[1]), int(ijk[2]))) continue;
    const float reach = depth[g.linearIndex(int(ijk[0]), int(ijk[1]), int(ijk[2]))];
    const int nx = g.dims[0], ny = g.dims[1];
    const Eigen::Vector3d x = g.indexToPhysical(
        Eigen::Vector3d(double(v % nx), double((v / nx) % ny), double(v / (std::size_t(nx) * ny))));
    if ((x - skeleton.joints[child].center).norm() < kJointGuard * reach) return true;
  }
  return false;
}

// Seeds of the walk along contact c's boundary `sheet`: beside a crease between the two parts, and
// beside free skin.
ContactCutPass::Seeds ContactCutPass::sheetSeeds(std::size_t c, const Pair& p, const std::vector<std::size_t>& sheet,
                                                 const std::vector<std::int32_t>& creaseContact) const {
  Seeds seeds;
  for (std::size_t v : sheet) {
    // A voxel cut by an earlier pass (body in the scan, background now) is a contact continued.
    std::uint8_t k = 0;
    nbh.forEach(v, [&](std::size_t w, float) {
      if (body.data[w]) return;
      if (creaseContact[w] == std::int32_t(c) || scanBody.data[w]) k = 1;
      else if (crease[w] == 2 && k == 0) k = 2;
    });
    // Skin that faces the other part across a gap (where the two part for a moment between two
    // stretches of contact) is not free: it does not keep the boundary.
    if (k == 2) {
      bool facesOther = false;
      nbh.forEach(v, [&](std::size_t w, float) {
        if (body.data[w] || facesOther) return;
        sandwichSides(body, w, kGapReach * options.creaseReach, [&](std::size_t w1, std::size_t w2, const Eigen::Vector3d&) {
          facesOther = makePair(seg[w1], seg[w2]) == p;
          return facesOther;
        });
      });
      if (facesOther) k = 0;
    }
    if (k == 1) seeds.crease.push_back(v);
    if (k == 2) seeds.skin.push_back(v);
  }
  return seeds;
}

// Distance (mm) along the sheet from the nearest seed; infinite where no seed is reached.
std::vector<float> ContactCutPass::alongSheet(const std::vector<std::size_t>& sheet,
                                              const std::unordered_map<std::size_t, std::size_t>& slot,
                                              const std::vector<std::size_t>& seeds) const {
  std::vector<float> dist(sheet.size(), std::numeric_limits<float>::infinity());
  using Entry = std::pair<float, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (std::size_t v : seeds) dist[slot.at(v)] = 0.f, queue.emplace(0.f, slot.at(v));
  while (!queue.empty()) {
    const auto [d, s] = queue.top();
    queue.pop();
    if (dist[s] != d) continue;
    nbh.forEach(sheet[s], [&](std::size_t w, float mm) {
      const auto it = slot.find(w);
      if (it == slot.end() || dist[it->second] <= d + mm) return;
      dist[it->second] = d + mm;
      queue.emplace(d + mm, it->second);
    });
  }
  return dist;
}

void ContactCutPass::cutSheet(std::size_t c, const std::vector<std::size_t>& sheet,
                              const std::vector<std::int32_t>& creaseContact, const std::vector<float>& depth,
                              const std::vector<std::size_t>& segmentVoxels,
                              std::vector<std::pair<std::size_t, std::size_t>>& cut) const {
  if (sheet.empty()) return;
  const float margin = float(kMargin * g.spacing.mean());
  const Pair p{report.contacts[c].boneA, report.contacts[c].boneB};
  std::unordered_map<std::size_t, std::size_t> slot;
  for (std::size_t s = 0; s < sheet.size(); ++s) slot[sheet[s]] = s;
  const Seeds seeds = sheetSeeds(c, p, sheet, creaseContact);
  const std::vector<float> toCrease = alongSheet(sheet, slot, seeds.crease), toSkin = alongSheet(sheet, slot, seeds.skin);
  const int larger = segmentVoxels[p.first] > segmentVoxels[p.second] ? p.first : p.second;
  for (std::size_t s = 0; s < sheet.size(); ++s) {
    const std::size_t v = sheet[s];
    const bool contact = std::isfinite(toCrease[s]) && !(toSkin[s] + margin < toCrease[s]) && !guarded(p, v, depth);
    if (!contact) continue;
    // Cut on the larger segment's side: the voxel itself, or its neighbours there.
    if (seg[v] == larger) {
      if (bone.data[v] < 0) cut.emplace_back(v, c);
      continue;
    }
    nbh.forEach(v, [&](std::size_t w, float) {
      if (body.data[w] && seg[w] == larger && bone.data[w] < 0) cut.emplace_back(w, c);
    });
  }
}

ContactSeparationReport cutContacts(MaskVolume& body, const MaskVolume& scanBody, const std::vector<std::uint8_t>& crease,
                                    const Volume<std::int16_t>& bone, const Skeleton& skeleton,
                                    const ContactSeparationOptions& options, const Neighbourhood& nbh) {
  return ContactCutPass{body, scanBody, crease, bone, skeleton, options, nbh}.run();
}

}  // namespace

ContactSeparationReport separateContacts(MaskVolume& body, const Volume<std::int16_t>& bone,
                                         const Skeleton& skeleton, const ContactSeparationOptions& options) {
  const ImageGrid& g = body.grid;
  if (!g.sameGridAs(bone.grid) || body.data.size() != g.voxelCount() || bone.data.size() != g.voxelCount())
    throw std::invalid_argument("contact separation: the body mask and the bone map are on different grids");
  if (options.creaseReach < 1)
    throw std::invalid_argument("contact separation: the crease reach must be at least one voxel");
  const Neighbourhood nbh(g);
  const MaskVolume scanBody = body;
  const std::vector<std::uint8_t> crease = creaseMap(scanBody, nbh, options);
  // Two passes: the second finds its segments in the body the first has cut, so tissue is not
  // given to a part it reached only through a contact now cut.
  ContactSeparationReport report = cutContacts(body, scanBody, crease, bone, skeleton, options, nbh);
  const ContactSeparationReport second = cutContacts(body, scanBody, crease, bone, skeleton, options, nbh);
  for (const ContactSeparationReport::Contact& c : second.contacts) {
    auto it = std::find_if(report.contacts.begin(), report.contacts.end(), [&](const auto& r) {
      return r.boneA == c.boneA && r.boneB == c.boneB;
    });
    if (it == report.contacts.end()) {
      report.contacts.push_back(c);
    } else {
      it->voxelsCut += c.voxelsCut;
      it->areaMm2 += c.areaMm2;
    }
  }
  report.voxelsCut += second.voxelsCut;
  std::sort(report.contacts.begin(), report.contacts.end(),
            [](const auto& a, const auto& b) { return std::make_pair(a.boneA, a.boneB) < std::make_pair(b.boneA, b.boneB); });
  return report;
}

}  // namespace repose
