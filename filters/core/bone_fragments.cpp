#include "bone_fragments.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "parallel_for.h"
#include "point_grid.h"

namespace repose {

namespace {

using V3 = Eigen::Vector3d;

bool compatible(BoneSide a, BoneSide b) { return a == BoneSide::None || b == BoneSide::None || a == b; }

std::string mm(double d) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << d << " mm";
  return s.str();
}

// What the search needs to know about one fragment.
struct Piece {
  std::vector<std::size_t> voxels;  // linear indices
  std::unique_ptr<PointGrid> surface;  // physical positions of its surface voxels
  BoneName kind;                    // of its label
  BoneSide side = BoneSide::None;   // of its centroid (None near the midline)
  std::map<int, int> touches;       // neighbouring component -> 26-neighbour voxel pairs
};

class FragmentPlacer {
public:
  FragmentPlacer(const ImageGrid& grid, const AutoRigOptions& options, RigBones& rb) : grid_(grid), rb_(rb) {
    limit_ = std::max(options.maxFragmentDistanceMm, options.maxFragmentDistanceVoxels * grid_.spacing.maxCoeff());
    band_ = options.midlineBandMm;
    cell_ = 2 * grid_.spacing.maxCoeff();
  }

  void run() {
    collect();
    if (rb_.fragments.empty()) return;
    // Its own kind first (touching, then near), so a piece of a hip bone that touches the femoral
    // head stays with its hip bone; then any bone it touches, then the nearest on its side.
    while (true) {
      if (propagateTouches(2) | placeNearest(2)) continue;
      if (!(propagateTouches(0) | placeNearest(1))) break;
    }
    leaveTheRestSoft();
  }

private:
  V3 physical(std::size_t p) const {
    const int nx = grid_.dims[0], ny = grid_.dims[1];
    return grid_.indexToPhysical(V3(double(p % nx), double((p / nx) % ny), double(p / (std::size_t(nx) * ny))));
  }

  void collect() {
    const auto& comps = rb_.components;
    std::vector<int> fragOf(comps.size(), -1);
    for (int c = 0; c < int(comps.size()); ++c) {
      if (rb_.boneOfComponent[c] >= 0) continue;
      fragOf[c] = int(rb_.fragments.size());
      BoneFragment f;
      f.comp = c;
      f.label = comps[c].label;
      f.voxels = comps[c].count;
      f.centroid = comps[c].centroid;
      rb_.fragments.push_back(f);
    }
    pieces_.resize(rb_.fragments.size());
    for (std::size_t p = 0; p < rb_.componentOf.size(); ++p) {
      const int c = rb_.componentOf[p];
      if (c >= 0 && fragOf[c] >= 0) pieces_[fragOf[c]].voxels.push_back(p);
    }
    parallelFor(pieces_.size(), [&](std::size_t f0, std::size_t f1) {
      for (std::size_t f = f0; f < f1; ++f) describe(int(f));
    }, 1);
  }

  // The fragment's kind, side, surface and the components it touches.
  void describe(int f) {
    Piece& piece = pieces_[f];
    const BoneFragment& frag = rb_.fragments[f];
    piece.kind = recogniseBone(rb_.table.nameOf(frag.label));
    // Its side: where it lies, or near the midline the side its label names (if any).
    const double dx = frag.centroid.x() - rb_.midX;
    piece.side = std::abs(dx) <= band_ ? piece.kind.side : dx > 0 ? BoneSide::Left : BoneSide::Right;
    std::vector<V3> surface;
    const int nx = grid_.dims[0], ny = grid_.dims[1];
    for (std::size_t p : piece.voxels) {
      const int i = int(p % nx), j = int((p / nx) % ny), k = int(p / (std::size_t(nx) * ny));
      bool edge = false;
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if (!grid_.contains(i + di, j + dj, k + dk)) {
              edge = true;
              continue;
            }
            const int c = rb_.componentOf[grid_.linearIndex(i + di, j + dj, k + dk)];
            if (c == frag.comp) continue;
            edge = true;
            if (c >= 0) ++piece.touches[c];
          }
      if (edge) surface.push_back(physical(p));
    }
    piece.surface = std::make_unique<PointGrid>(std::move(surface), cell_);
  }

  bool sameKind(int f, int bone) const {
    const Piece& piece = pieces_[f];
    const RigBone& b = rb_.bones[bone];
    if (!piece.kind.known()) return b.sourceLabel == rb_.fragments[f].label;
    return b.anatomy.type == piece.kind.type && b.anatomy.level == piece.kind.level;  // L3 is not L2
  }

  // Preference of bone `bone` for fragment f: own kind on a compatible side, compatible side, any.
  int rank(int f, int bone) const {
    if (!compatible(pieces_[f].side, rb_.bones[bone].anatomy.side)) return 0;
    return sameKind(f, bone) ? 2 : 1;
  }

  void place(int f, int bone, const std::string& why, double distance) {
    BoneFragment& frag = rb_.fragments[f];
    frag.bone = bone;
    frag.why = why;
    frag.distanceMm = distance;
    rb_.boneOfComponent[frag.comp] = bone;
    RigBone& b = rb_.bones[bone];
    b.voxels += frag.voxels;
    const BoneComponent& c = rb_.components[frag.comp];
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = std::min(b.lo[d], c.lo[d]);
      b.hi[d] = std::max(b.hi[d], c.hi[d]);
    }
  }

  // Fragments touching a bone of rank >= minRank (through placed fragments) go to it, repeated
  // until nothing moves; returns whether any did.
  bool propagateTouches(int minRank) {
    bool any = false;
    for (bool changed = true; changed;) {
      changed = false;
      for (int f = 0; f < int(pieces_.size()); ++f) {
        if (rb_.fragments[f].bone >= 0) continue;
        int best = -1, bestRank = -1, bestCount = 0;
        for (const auto& [c, count] : pieces_[f].touches) {
          const int bone = rb_.boneOfComponent[c];
          if (bone < 0) continue;
          const int r = rank(f, bone);
          if (r < minRank) continue;
          if (r > bestRank || (r == bestRank && count > bestCount)) {
            best = bone;
            bestRank = r;
            bestCount = count;
          }
        }
        if (best >= 0) {
          place(f, best, "touches " + rb_.bones[best].name, 0);
          changed = any = true;
        }
      }
    }
    return any;
  }

  // Distance from fragment f to every bone (through placed fragments too) within the limit.
  std::map<int, double> distances(int f) const {
    std::map<int, double> d;
    const PointGrid& mine = *pieces_[f].surface;
    auto consider = [&](int bone, const PointGrid& target) {
      if (target.boxDistance(mine) > limit_) return;
      const double x = target.closestPair(mine.points(), limit_).distance;
      if (x <= limit_ && (!d.count(bone) || x < d[bone])) d[bone] = x;
    };
    for (int b = 0; b < int(rb_.bones.size()); ++b) consider(b, *rb_.bones[b].surface);
    for (int g = 0; g < int(pieces_.size()); ++g)
      if (g != f && rb_.fragments[g].bone >= 0) consider(rb_.fragments[g].bone, *pieces_[g].surface);
    return d;
  }

  // One round: every unplaced fragment goes to its best bone of rank >= minRank (1: a compatible
  // side; 2: also its own kind) within reach of what is placed now.
  bool placeNearest(int minRank) {
    std::vector<int> open;
    for (int f = 0; f < int(pieces_.size()); ++f)
      if (rb_.fragments[f].bone < 0) open.push_back(f);
    std::vector<std::pair<int, double>> choice(open.size(), {-1, 0.0});
    parallelFor(open.size(), [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) {
        const int f = open[i];
        int best = -1, bestRank = 0;
        double bestD = 0;
        for (const auto& [bone, d] : distances(f)) {
          const int r = rank(f, bone);
          if (r < minRank) continue;
          if (r > bestRank || (r == bestRank && r > 0 && d < bestD)) {
            best = bone;
            bestRank = r;
            bestD = d;
          }
        }
        choice[i] = {best, bestD};
      }
    }, 1);
    bool placed = false;
    for (std::size_t i = 0; i < open.size(); ++i) {
      const auto [bone, d] = choice[i];
      if (bone < 0) continue;
      const int f = open[i];
      const bool own = sameKind(f, bone);
      const std::string where = pieces_[f].side == BoneSide::None ? "" : " on its side";
      place(f, bone,
            "nearest " + std::string(own ? boneTypeName(pieces_[f].kind.type) : "bone") + where + ", " + mm(d), d);
      placed = true;
    }
    return placed;
  }

  void leaveTheRestSoft() {
    bool any = false;
    for (BoneFragment& frag : rb_.fragments) {
      if (frag.bone >= 0) continue;
      any = true;
      frag.why = "touches no bone, and no bone" +
                 std::string(pieces_[&frag - rb_.fragments.data()].side == BoneSide::None ? "" : " on its side") +
                 " lies within " + mm(limit_) + ": left as soft tissue";
      frag.distanceMm = limit_;
    }
    if (!any) return;
    int value = 0;
    for (const LabelInfo& l : rb_.table.labels) value = std::max(value, l.value);
    for (const BoneComponent& c : rb_.components) value = std::max(value, c.label);
    for (const RigBone& b : rb_.bones) value = std::max(value, b.value);
    rb_.unassignedValue = value + 1;
    rb_.table.labels.push_back({rb_.unassignedValue, "unassigned_bone_fragments", LabelKind::Soft});
  }

  const ImageGrid& grid_;
  RigBones& rb_;
  double limit_ = 0, band_ = 0, cell_ = 1;
  std::vector<Piece> pieces_;
};

}  // namespace

void assignFragments(const LabelVolume& labels, const AutoRigOptions& options, RigBones& out) {
  FragmentPlacer(labels.grid, options, out).run();
}

LabelVolume relabelBones(const LabelVolume& labels, const RigBones& rb) {
  LabelVolume out = labels;
  for (std::size_t p = 0; p < out.data.size(); ++p) {
    const int c = rb.componentOf[p];
    if (c < 0) continue;
    const int bone = rb.boneOfComponent[c];
    out.data[p] = bone >= 0 ? rb.bones[bone].value : rb.unassignedValue;
  }
  return out;
}

}  // namespace repose
