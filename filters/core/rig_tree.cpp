#include "rig_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

namespace repose {

namespace {

using T = BoneType;
using V3 = Eigen::Vector3d;

bool isPelvisLike(const BoneName& b) {
  return b.type == T::HipBone || b.type == T::Pelvis || b.type == T::Sacrum || b.type == T::Coccyx ||
         (b.type == T::Vertebra && b.level[0] == 'S');
}
bool isSpineType(const BoneName& b) {
  return (b.type == T::Vertebra && b.level[0] != 'S') || b.type == T::CervicalSpine || b.type == T::ThoracicSpine ||
         b.type == T::LumbarSpine || b.type == T::Spine;
}
bool isRider(const BoneName& b) {  // ribs and sternum: carried by the spine, never joints
  return b.type == T::Rib || b.type == T::Ribcage || b.type == T::Sternum || b.type == T::CostalCartilage;
}
bool isTrunk(const BoneName& b) { return isSpineType(b) || isRider(b); }
bool isCervical(const BoneName& b) {
  return b.type == T::CervicalSpine || (b.type == T::Vertebra && b.level[0] == 'C');
}
bool isForearm(const BoneName& b) { return b.type == T::Radius || b.type == T::Ulna || b.type == T::Forearm; }
bool isShank(const BoneName& b) { return b.type == T::Tibia || b.type == T::Fibula; }

// Craniocaudal order along the spine: the pelvis 0, L5 1 ... C1 24; -1 when unknown (whole spine).
int spineRank(const BoneName& b) {
  if (isPelvisLike(b)) return 0;
  switch (b.type) {
    case T::LumbarSpine: return 3;
    case T::ThoracicSpine: return 11;
    case T::CervicalSpine: return 21;
    case T::Vertebra: {
      const int n = std::stoi(b.level.substr(1));
      return b.level[0] == 'L' ? 6 - n : b.level[0] == 'T' ? 18 - n : 25 - n;
    }
    default: return -1;
  }
}

// Bones that move as one joint, by family and side (forearm, hand, shank, foot).
int familyOf(const BoneName& b) {
  if (isForearm(b)) return 1;
  if (b.type == T::Hand) return 2;
  if (isShank(b)) return 3;
  if (b.type == T::Foot) return 4;
  return 0;
}

/// Tier of `p` as the parent bone of `c`: 0 anatomy forbids it, 1 preferred, 2 fallback, 3 any
/// (an unrecognised child).
int parentTier(const BoneName& c, const BoneName& p) {
  if (c.side != BoneSide::None && p.side != BoneSide::None && c.side != p.side) return 0;
  if (!c.known()) return 3;
  if (!p.known()) return 0;
  if (isSpineType(c)) {
    if (!isPelvisLike(p) && !isSpineType(p)) return 0;
    const int rc = spineRank(c), rp = spineRank(p);
    return rc >= 0 && rp >= 0 && rp >= rc ? 0 : 1;
  }
  switch (c.type) {
    case T::Skull: return isCervical(p) ? 1 : isSpineType(p) ? 2 : 0;
    case T::Mandible: return p.type == T::Skull ? 1 : 0;
    case T::Clavicle: return p.type == T::Sternum ? 1 : isTrunk(p) ? 2 : 0;
    case T::Scapula: return p.type == T::Clavicle ? 1 : isTrunk(p) ? 2 : 0;
    case T::Humerus: return p.type == T::Scapula ? 1 : isTrunk(p) ? 2 : 0;
    case T::Radius: case T::Ulna: case T::Forearm: return p.type == T::Humerus ? 1 : 0;
    case T::Hand: return isForearm(p) ? 1 : p.type == T::Hand ? 2 : 0;
    case T::Femur: return isPelvisLike(p) ? 1 : 0;
    case T::Patella: return p.type == T::Femur ? 1 : isShank(p) ? 2 : 0;
    case T::Tibia: case T::Fibula: return p.type == T::Femur ? 1 : 0;
    case T::Foot: return isShank(p) ? 1 : p.type == T::Foot ? 2 : 0;
    case T::HipBone: case T::Pelvis: case T::Sacrum: case T::Coccyx: case T::Vertebra:
      return isSpineType(p) ? 1 : 0;  // a pelvis group that is not the root
    case T::Rib: case T::Ribcage: case T::Sternum: case T::CostalCartilage:
      return isPelvisLike(p) || isSpineType(p) ? 1 : 0;  // a ribcage with no spine to ride on
    default: return 0;
  }
}

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int a) { return p[a] == a ? a : p[a] = find(p[a]); }
  void unite(int a, int b) { p[find(a)] = find(b); }
};

struct Edge {
  int parentGroup = -1, childBone = -1, parentBone = -1, tier = 0;
  double gap = std::numeric_limits<double>::infinity();
  std::size_t size = 0;
  bool beyond = false;
  V3 onChild = V3::Zero(), onParent = V3::Zero();
};
bool better(const Edge& a, const Edge& b) {
  return a.gap < b.gap - 1e-9 || (std::abs(a.gap - b.gap) <= 1e-9 && a.size > b.size);
}

class TreePlanner {
public:
  TreePlanner(const ImageGrid& grid, const RigBones& rb, const std::vector<std::vector<BoneContact>>& contacts,
              double contactMm, const AutoRigOptions& options)
      : grid_(grid), rb_(rb), bones_(rb.bones), contacts_(contacts), contactMm_(contactMm), options_(options),
        B_(int(rb.bones.size())), uf_(B_) {}

  RigTree run() {
    fuse();
    formGroups();
    findEdges();
    chooseRoot();
    spanTree();
    return result();
  }

private:
  const BoneName& anat(int b) const { return bones_[b].anatomy; }

  double contactGap(int a, int o) const {
    const BoneContact* c = findContact(contacts_, a, o);
    return c ? double(c->dmin) : std::numeric_limits<double>::infinity();
  }
  // Surface distance (voxel centres) between two bones within `limit`, exact unless maxQueries.
  PointGrid::Pair distance(int a, int o, double limit, std::size_t maxQueries = std::size_t(-1)) const {
    const PointGrid& ga = *bones_[a].surface;
    const PointGrid& go = *bones_[o].surface;
    if (go.boxDistance(ga) > limit) return {std::numeric_limits<double>::infinity(), 0, 0};
    return go.closestPair(ga.points(), limit, maxQueries);
  }

  // Fused groups: the pelvis, the forearm/hand/shank/foot of each side, patellae, ribs and sternum.
  void fuse() {
    const double reach = std::max(options_.maxAnatomicGapMm, contactMm_);
    for (int a = 0; a < B_; ++a)
      for (const BoneContact& c : contacts_[a]) {
        const BoneName &x = anat(a), &y = anat(c.other);
        const bool sameSide = x.side == y.side;
        if ((isPelvisLike(x) && isPelvisLike(y)) || (sameSide && familyOf(x) != 0 && familyOf(x) == familyOf(y)))
          uf_.unite(a, c.other);
      }
    // Parts of the pelvis and of a limb segment that do not touch still belong together.
    for (int a = 0; a < B_; ++a)
      for (int o = a + 1; o < B_; ++o) {
        const BoneName &x = anat(a), &y = anat(o);
        const bool together = (isPelvisLike(x) && isPelvisLike(y)) ||
                              (x.side == y.side && familyOf(x) != 0 && familyOf(x) == familyOf(y));
        if (together && uf_.find(a) != uf_.find(o) && distance(a, o, reach).distance <= reach) uf_.unite(a, o);
      }
    for (int a = 0; a < B_; ++a) {  // a patella rides with its femur (else its tibia)
      if (anat(a).type != T::Patella) continue;
      for (int tier : {1, 2}) {
        int host = -1;
        double best = reach;
        for (int o = 0; o < B_; ++o) {
          if (o == a || parentTier(anat(a), anat(o)) != tier) continue;
          const double d = std::min(contactGap(a, o), distance(a, o, best).distance);
          if (d <= best) { best = d; host = o; }
        }
        if (host >= 0) { uf_.unite(a, host); patellaHost_[a] = host; break; }
      }
    }
    fuseRiders();
  }

  // Each rib rides with its own thoracic vertebra (rib_left_7 with T7) when it is there; else a rib,
  // sternum or ribcage rides with the thoracic vertebra it touches closest, or any spine bone it
  // touches; else with the nearest thoracic vertebra or riding rib (the sternum across the costal
  // cartilage), else the nearest spine bone.
  void fuseRiders() {
    auto thoracic = [&](int b) {
      const BoneName& n = anat(b);
      return n.type == T::ThoracicSpine || n.type == T::Spine || (n.type == T::Vertebra && n.level[0] == 'T');
    };
    std::vector<std::pair<int, int>> rides;  // (rider, spine bone)
    for (int a = 0; a < B_; ++a) {
      if (!isRider(anat(a))) continue;
      int host = -1;
      if (anat(a).type == T::Rib && !anat(a).level.empty())
        for (int o = 0; o < B_; ++o)
          if (anat(o).type == T::Vertebra && anat(o).level == "T" + anat(a).level) host = o;
      for (bool anySpine : {false, true}) {
        if (host >= 0) break;
        double gap = std::numeric_limits<double>::infinity();
        for (const BoneContact& c : contacts_[a])
          if (isSpineType(anat(c.other)) && (anySpine || thoracic(c.other)) && c.dmin < gap) {
            gap = c.dmin;
            host = c.other;
          }
      }
      if (host >= 0) rides.emplace_back(a, host);
    }
    for (const auto& [a, host] : rides) uf_.unite(a, host);
    auto ridden = [&](int b) {
      for (int o = 0; o < B_; ++o)
        if (uf_.find(o) == uf_.find(b) && isSpineType(anat(o))) return true;
      return false;
    };
    for (bool anySpine : {false, true})
      for (bool changed = true; changed;) {
        changed = false;
        for (int a = 0; a < B_; ++a) {
          if (!isRider(anat(a)) || ridden(a)) continue;
          std::vector<int> hosts;
          for (int o = 0; o < B_; ++o)
            if (uf_.find(o) != uf_.find(a) &&
                ((isSpineType(anat(o)) && (anySpine || thoracic(o))) || (isRider(anat(o)) && ridden(o))))
              hosts.push_back(o);
          const int host = nearestOf(a, hosts, 400.0);  // mm: the sternum lies 10-15 cm before the spine
          if (host >= 0) {
            uf_.unite(a, host);
            changed = true;
          }
        }
      }
  }

  // The bone of `candidates` nearest to bone a within `limit` (mm), -1 when none; candidates are
  // tried nearest box first, with a sample of a's surface (a far search scans many cells).
  int nearestOf(int a, std::vector<int> candidates, double limit) const {
    const PointGrid& ga = *bones_[a].surface;
    std::vector<std::pair<double, int>> order;
    for (int o : candidates) order.emplace_back(bones_[o].surface->boxDistance(ga), o);
    std::sort(order.begin(), order.end());
    int best = -1;
    for (const auto& [box, o] : order) {
      if (box > limit) break;
      const double d = bones_[o].surface->closestPair(ga.points(), limit, 64).distance;
      if (d < limit) {
        limit = d;
        best = o;
      }
    }
    return best;
  }

  void formGroups() {
    std::map<int, int> groupOfRep;
    groupOf_.assign(B_, -1);
    for (int a = 0; a < B_; ++a) {
      const int rep = uf_.find(a);
      auto it = groupOfRep.find(rep);
      if (it == groupOfRep.end()) {
        it = groupOfRep.emplace(rep, int(members_.size())).first;
        members_.emplace_back();
      }
      groupOf_[a] = it->second;
      members_[it->second].push_back(a);
    }
    G_ = int(members_.size());
    primary_.assign(G_, -1);
    voxels_.assign(G_, 0);
    centroid_.assign(G_, V3::Zero());
    for (int g = 0; g < G_; ++g) {
      for (int a : members_[g]) {
        voxels_[g] += bones_[a].voxels;
        centroid_[g] += bones_[a].centroid * double(bones_[a].voxels);
        // The group's largest bone that is not a rider or a patella names and places it.
        auto weight = [&](int b) { return (isRider(anat(b)) || anat(b).type == T::Patella) ? 0 : 1; };
        const int p = primary_[g];
        if (p < 0 || weight(a) > weight(p) || (weight(a) == weight(p) && bones_[a].voxels > bones_[p].voxels))
          primary_[g] = a;
      }
      centroid_[g] /= double(std::max<std::size_t>(1, voxels_[g]));
    }
  }

  // A bone may articulate its group with a parent unless it only rides in the group.
  bool canBeChild(int a) const {
    const int p = primary_[groupOf_[a]];
    return a == p || !(isRider(anat(a)) || anat(a).type == T::Patella);
  }

  void findEdges() {
    edges_.assign(G_, {});
    touchesAny_.assign(G_, 0);
    auto add = [&](int g, const Edge& e) {
      for (Edge& x : edges_[g])
        if (x.parentGroup == e.parentGroup && x.tier == e.tier) {
          if (better(e, x)) x = e;
          return;
        }
      edges_[g].push_back(e);
    };
    for (int a = 0; a < B_; ++a)
      for (const BoneContact& c : contacts_[a]) {  // c: the other bone's voxels near a
        const int o = c.other, g = groupOf_[a], h = groupOf_[o];
        if (g == h) continue;
        touchesAny_[g] = 1;
        if (!canBeChild(a)) continue;
        const int tier = parentTier(anat(a), anat(o));
        if (tier == 0) continue;
        Edge e;
        e.parentGroup = h;
        e.childBone = a;
        e.parentBone = o;
        e.tier = tier;
        e.gap = c.dmin;
        e.size = c.near.size();
        add(g, e);
      }
    // A preferred parent out of contact but within maxAnatomicGapMm is still the parent.
    for (int g = 0; g < G_; ++g) {
      const bool hasPreferred = std::any_of(edges_[g].begin(), edges_[g].end(), [](const Edge& e) { return e.tier == 1; });
      if (hasPreferred) continue;
      for (int a : members_[g]) {
        if (!canBeChild(a)) continue;
        for (int o = 0; o < B_; ++o) {
          if (groupOf_[o] == g || parentTier(anat(a), anat(o)) != 1) continue;
          const PointGrid::Pair p = distance(a, o, options_.maxAnatomicGapMm);
          if (!(p.distance <= options_.maxAnatomicGapMm)) continue;
          Edge e;
          e.parentGroup = groupOf_[o];
          e.childBone = a;
          e.parentBone = o;
          e.tier = 1;
          e.gap = p.distance;
          e.size = 1;
          e.beyond = true;
          e.onChild = bones_[a].surface->points()[p.query];
          e.onParent = bones_[o].surface->points()[p.index];
          add(g, e);
        }
      }
    }
  }

  void chooseRoot() {
    auto largest = [&](auto&& pick) {
      int r = -1;
      for (int g = 0; g < G_; ++g)
        if (pick(g) && (r < 0 || voxels_[g] > voxels_[r])) r = g;
      return r;
    };
    root_ = largest([&](int g) { return isPelvisLike(anat(primary_[g])); });
    pelvisRoot_ = root_ >= 0;
    if (root_ < 0) root_ = largest([&](int g) { return isSpineType(anat(primary_[g])); });
    if (root_ < 0) {
      double xlo = 1e30, xhi = -1e30;
      for (const RigBone& b : bones_) {
        xlo = std::min(xlo, b.centroid.x());
        xhi = std::max(xhi, b.centroid.x());
      }
      const double band = std::max(0.1 * (xhi - xlo), 2 * grid_.spacing.maxCoeff());
      root_ = largest([&](int g) { return std::abs(centroid_[g].x() - rb_.midX) <= band; });
    }
    if (root_ < 0) root_ = largest([](int) { return true; });
  }

  // Prim's algorithm from the root over the edges of each group's current tier; a group whose
  // preferred parents never join the tree falls back to its next tier.
  void spanTree() {
    inTree_.assign(G_, 0);
    link_.assign(G_, Edge{});
    parent_.assign(G_, -1);
    std::vector<int> tier(G_, 0);
    for (int g = 0; g < G_; ++g)
      for (const Edge& e : edges_[g]) tier[g] = tier[g] == 0 ? e.tier : std::min(tier[g], e.tier);
    inTree_[root_] = 1;
    order_ = {root_};
    while (true) {
      int next = -1;
      Edge best;
      for (int g = 0; g < G_; ++g) {
        if (inTree_[g]) continue;
        for (const Edge& e : edges_[g])
          if (e.tier == tier[g] && inTree_[e.parentGroup] && (next < 0 || better(e, best))) {
            next = g;
            best = e;
          }
      }
      if (next >= 0) {
        inTree_[next] = 1;
        link_[next] = best;
        parent_[next] = best.parentGroup;
        order_.push_back(next);
        continue;
      }
      bool raised = false;  // no edge of the current tiers reaches the tree: fall back
      for (int g = 0; g < G_; ++g) {
        if (inTree_[g]) continue;
        int t = 0;
        for (const Edge& e : edges_[g])
          if (e.tier > tier[g] && (t == 0 || e.tier < t)) t = e.tier;
        if (t > 0) {
          tier[g] = t;
          raised = true;
        }
      }
      if (!raised) break;
    }
  }

  std::string jointName(int g) const {
    const int pb = primary_[g];
    const BoneName& a = anat(pb);
    const int parent = parent_[g];
    if (g == root_ && pelvisRoot_) return "pelvis";
    if (isSpineType(a) && parent == root_ && pelvisRoot_) return "spine";
    if (isCervical(a) && (parent < 0 || !isCervical(anat(primary_[parent])))) return "neck";
    if (a.type == T::Skull) {
      for (int p = parent; p >= 0; p = parent_[p])
        if (isCervical(anat(primary_[p]))) return "head";
      return "neck";
    }
    const std::string n = jointNameOf(a.type, a.side, a.level);
    return n.empty() ? bones_[pb].name : n;
  }

  RigTree result() {
    RigTree t;
    t.jointOfBone.assign(B_, -1);
    t.note.assign(B_, "");
    std::vector<int> jointOfGroup(G_, -1);
    std::set<std::string> used;
    for (int g : order_) {
      const std::string name = jointName(g);
      std::string unique = name;
      for (int n = 2; used.count(unique); ++n) unique = name + "_" + std::to_string(n);
      used.insert(unique);
      PlannedJoint j;
      j.name = unique;
      j.bones = members_[g];
      if (g != root_) {
        const Edge& e = link_[g];
        j.parent = jointOfGroup[parent_[g]];
        j.childBone = e.childBone;
        j.parentBone = e.parentBone;
        j.gapMm = e.gap;
        j.beyondContact = e.beyond;
        j.closestOnChild = e.onChild;
        j.closestOnParent = e.onParent;
      }
      jointOfGroup[g] = int(t.joints.size());
      for (int a : members_[g]) t.jointOfBone[a] = jointOfGroup[g];
      t.joints.push_back(std::move(j));
    }
    for (int a = 0; a < B_; ++a) {
      const int g = groupOf_[a];
      if (inTree_[g]) {
        if (patellaHost_.count(a)) t.note[a] = "rides with " + bones_[patellaHost_.at(a)].name;
        continue;
      }
      t.note[a] = leftOutReason(g);
    }
    return t;
  }

  std::string leftOutReason(int g) const {
    std::ostringstream s;
    if (edges_[g].empty()) {
      if (touchesAny_[g]) {
        s << "touches only bones anatomy forbids as the parent of a " << boneTypeName(anat(primary_[g]).type);
        return s.str();
      }
      s << "not within " << int(std::lround(contactMm_ - grid_.spacing.maxCoeff())) << " mm of the skeleton";
      return s.str();
    }
    std::set<std::string> parents;
    for (const Edge& e : edges_[g]) parents.insert(bones_[e.parentBone].name);
    s << "its possible parents (";
    bool first = true;
    for (const std::string& p : parents) {
      s << (first ? "" : ", ") << p;
      first = false;
    }
    s << ") are not in the skeleton";
    return s.str();
  }

  const ImageGrid& grid_;
  const RigBones& rb_;
  const std::vector<RigBone>& bones_;
  const std::vector<std::vector<BoneContact>>& contacts_;
  const double contactMm_;
  const AutoRigOptions& options_;
  const int B_;
  UnionFind uf_;
  std::map<int, int> patellaHost_;
  int G_ = 0, root_ = -1;
  bool pelvisRoot_ = false;
  std::vector<int> groupOf_, primary_;
  std::vector<std::vector<int>> members_;
  std::vector<std::size_t> voxels_;
  std::vector<V3> centroid_;
  std::vector<std::vector<Edge>> edges_;
  std::vector<char> touchesAny_, inTree_;
  std::vector<Edge> link_;
  std::vector<int> parent_, order_;
};

}  // namespace

RigTree planSkeleton(const ImageGrid& grid, const RigBones& bones, const std::vector<std::vector<BoneContact>>& contacts,
                     double contactMm, const AutoRigOptions& options) {
  return TreePlanner(grid, bones, contacts, contactMm, options).run();
}

}  // namespace repose
