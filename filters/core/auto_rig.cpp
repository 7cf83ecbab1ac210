#include "auto_rig.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {

namespace {

using V3 = Eigen::Vector3d;

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
std::string firstToken(const std::string& name) {
  const std::string n = lower(name);
  return n.substr(0, n.find('_'));
}
bool isPelvisLike(const std::string& name) {
  const std::string n = lower(name), t = firstToken(name);
  return t == "hip" || t == "pelvis" || t == "sacrum" || t == "coccyx" || n == "vertebrae_s1" ||
         n == "vertebra_s1";
}
bool isRibLike(const std::string& name) {
  const std::string t = firstToken(name);
  return t == "rib" || t == "ribs" || t == "ribcage" || t == "sternum" || t == "costal";
}
bool isSpineLike(const std::string& name) {
  const std::string t = firstToken(name);
  return !isPelvisLike(name) && (t == "spine" || t == "vertebra" || t == "vertebrae");
}
enum class BallHint { Yes, No, Unknown };
BallHint ballHint(const std::string& name) {
  const std::string t = firstToken(name);
  if (t == "femur" || t == "humerus") return BallHint::Yes;
  static const std::set<std::string> hinges = {"tibia", "fibula", "patella", "foot", "hand", "forearm", "radius",
                                               "ulna", "spine", "vertebra", "vertebrae", "skull", "scapula",
                                               "clavicula", "clavicle", "rib", "ribs", "ribcage", "sternum"};
  return hinges.count(t) ? BallHint::No : BallHint::Unknown;
}

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int a) { return p[a] == a ? a : p[a] = find(p[a]); }
  void unite(int a, int b) { p[find(a)] = find(b); }
};

struct Component {
  int label = 0;
  std::size_t count = 0;
  V3 indexSum = V3::Zero();
  std::array<int, 3> lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{-1, -1, -1};
  bool cut = false;
};

struct Bone {
  int comp = 0, sourceLabel = 0, value = 0;
  std::string name;
  std::size_t count = 0;
  V3 centroid = V3::Zero();  // physical
  std::array<int, 3> lo{}, hi{};
  bool cut = false;
  std::vector<std::size_t> boundary;  // linear voxel indices
};

// Boundary voxels of bone `other` within the adjacency threshold of one bone, with distances.
struct Contact {
  int other = -1;
  float dmin = std::numeric_limits<float>::max();
  std::vector<std::pair<std::size_t, float>> near;
};

struct SphereFit {
  V3 c = V3::Zero();
  double r = 0, rms = 1e30;
  bool ok = false;
};

SphereFit fitSphereOnce(const std::vector<V3>& pts) {
  SphereFit f;
  const int n = int(pts.size());
  if (n < 6) return f;
  V3 mean = V3::Zero();
  for (const V3& p : pts) mean += p;
  mean /= n;
  // Algebraic fit: |p|^2 = 2 c.p + (r^2 - |c|^2), in coordinates centred on the mean.
  Eigen::MatrixXd A(n, 4);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const V3 q = pts[i] - mean;
    A.row(i) << 2 * q.x(), 2 * q.y(), 2 * q.z(), 1;
    b(i) = q.squaredNorm();
  }
  const Eigen::Vector4d x = A.colPivHouseholderQr().solve(b);
  V3 c = x.head<3>();
  double r2 = x(3) + c.squaredNorm();
  if (!(r2 > 0) || !std::isfinite(r2)) return f;
  double r = std::sqrt(r2);
  // Gauss-Newton on the geometric residuals |p - c| - r.
  for (int it = 0; it < 8; ++it) {
    Eigen::MatrixXd J(n, 4);
    Eigen::VectorXd res(n);
    for (int i = 0; i < n; ++i) {
      const V3 d = pts[i] - mean - c;
      const double len = std::max(d.norm(), 1e-9);
      res(i) = len - r;
      J.row(i) << -d.x() / len, -d.y() / len, -d.z() / len, -1;
    }
    const Eigen::Vector4d step = J.colPivHouseholderQr().solve(-res);
    c += step.head<3>();
    r += step(3);
    if (step.norm() < 1e-6) break;
  }
  double ss = 0;
  for (const V3& p : pts) {
    const double e = (p - mean - c).norm() - r;
    ss += e * e;
  }
  f.c = c + mean;
  f.r = std::abs(r);
  f.rms = std::sqrt(ss / n);
  f.ok = std::isfinite(f.rms) && std::isfinite(f.r);
  return f;
}

// Fit, drop the outliers (points of the bone's neck or shaft near the socket rim), refit.
SphereFit fitSphere(std::vector<V3> pts, double voxel) {
  SphereFit f = fitSphereOnce(pts);
  for (int round = 0; round < 2 && f.ok; ++round) {
    const double tol = std::max(voxel, 2.5 * f.rms);
    std::vector<V3> kept;
    for (const V3& p : pts)
      if (std::abs((p - f.c).norm() - f.r) <= tol) kept.push_back(p);
    if (kept.size() == pts.size() || kept.size() < 6) break;
    pts.swap(kept);
    f = fitSphereOnce(pts);
  }
  return f;
}

// Pose names for the built-in phantom's and TotalSegmentator's bone names.
std::string mapName(const std::string& boneName) {
  const std::string n = lower(boneName);
  static const std::map<std::string, std::string> exact = {{"spine", "spine"}, {"skull", "neck"}};
  if (auto it = exact.find(n); it != exact.end()) return it->second;
  static const std::map<std::string, std::string> sided = {
      {"femur", "hip"},          {"tibia", "knee"},         {"foot", "ankle"},       {"humerus", "shoulder"},
      {"forearm", "elbow"},      {"hand", "wrist"},         {"scapula", "scapula"},  {"clavicula", "clavicle"},
      {"clavicle", "clavicle"},  {"patella", "patella"},    {"fibula", "fibula"}};
  for (const char* side : {"left", "right"}) {
    const std::string suffix = std::string("_") + side;
    if (n.size() > suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0) {
      const std::string part = n.substr(0, n.size() - suffix.size());
      if (auto it = sided.find(part); it != sided.end()) return std::string(side) + "_" + it->second;
    }
  }
  for (const char* prefix : {"vertebrae_", "vertebra_"}) {
    const std::string p = prefix;
    if (n.compare(0, p.size(), p) == 0) return "vertebra_" + boneName.substr(p.size());
  }
  return "";
}

}  // namespace

std::string standardJointName(const std::string& boneName) { return mapName(boneName); }

std::string AutoRigReport::text() const {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  out << "joints: " << joints.size() << "\n";
  for (const JointInfo& j : joints) {
    out << "  " << j.name << " (parent " << (j.parent.empty() ? "none" : j.parent) << "): " << j.method;
    if (!j.parent.empty()) out << ", gap " << j.gapMm << " mm";
    if (j.method == "sphere fit") out << ", radius " << j.radiusMm << " mm, rms " << j.fitRmsMm << " mm";
    out << "\n";
  }
  out << "bones: " << bones.size() << "\n";
  for (const Bone& b : bones) {
    out << "  " << b.name << " (label " << b.label;
    if (b.label != b.sourceLabel) out << ", from " << b.sourceLabel;
    out << ", " << b.voxels << " voxels): " << (b.joint.empty() ? "left out" : "joint " + b.joint);
    if (b.cutByFieldOfView) out << "; cut by the field of view";
    if (!b.note.empty()) out << "; " << b.note;
    out << "\n";
  }
  if (!missingBones.empty()) {
    out << "missing bones (no voxels):";
    for (const std::string& m : missingBones) out << " " << m;
    out << "\n";
  }
  out << "noise: " << noiseComponents << " components, " << noiseVoxels << " voxels ignored\n";
  return out.str();
}

AutoRigResult autoRig(const LabelVolume& labels, const LabelTable& table, const AutoRigOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const ImageGrid& grid = labels.grid;
  if (grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0)
    throw std::invalid_argument("autoRig: the label volume is empty");
  if (labels.data.size() != grid.voxelCount())
    throw std::invalid_argument("autoRig: the label volume has " + std::to_string(labels.data.size()) +
                                " values for " + std::to_string(grid.voxelCount()) + " voxels");
  if (!(grid.spacing.array() > 0).all()) throw std::invalid_argument("autoRig: the spacing must be positive");
  if (!(options.maxGapMm >= 0) || !(options.maxGapVoxels >= 0) || !(options.noiseFraction >= 0) ||
      options.noiseFraction > 1)
    throw std::invalid_argument("autoRig: gaps must be >= 0 and the noise fraction within [0, 1]");

  const int nx = grid.dims[0], ny = grid.dims[1];
  const std::size_t N = grid.voxelCount();
  const V3 h = grid.spacing;
  const double hmax = h.maxCoeff();

  // ---- bone labels
  int maxLabel = 0;
  for (std::int32_t v : labels.data) maxLabel = std::max<int>(maxLabel, v);
  std::vector<char> isBone(std::size_t(maxLabel) + 1, 0);
  for (const LabelInfo& l : table.labels)
    if (l.kind == LabelKind::Bone && l.value >= 0 && l.value <= maxLabel) isBone[l.value] = 1;

  // ---- 6-connected components of the bone labels (BFS)
  std::vector<std::int32_t> comp(N, -1);
  std::vector<Component> comps;
  std::vector<std::size_t> queue;
  auto coords = [&](std::size_t p, int& i, int& j, int& k) {
    i = int(p % nx);
    j = int((p / nx) % ny);
    k = int(p / (std::size_t(nx) * ny));
  };
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  for (std::size_t s = 0; s < N; ++s) {
    const int v = labels.data[s];
    if (v <= 0 || !isBone[v] || comp[s] >= 0) continue;
    const int id = int(comps.size());
    comps.emplace_back();
    Component& c = comps.back();
    c.label = v;
    queue.assign(1, s);
    comp[s] = id;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::size_t p = queue[q];
      int ijk[3];
      coords(p, ijk[0], ijk[1], ijk[2]);
      ++c.count;
      c.indexSum += V3(ijk[0], ijk[1], ijk[2]);
      for (int d = 0; d < 3; ++d) {
        c.lo[d] = std::min(c.lo[d], ijk[d]);
        c.hi[d] = std::max(c.hi[d], ijk[d]);
        if (ijk[d] == 0 || ijk[d] == grid.dims[d] - 1) c.cut = true;
        for (int sgn : {-1, 1}) {
          const int nd = ijk[d] + sgn;
          if (nd < 0 || nd >= grid.dims[d]) continue;
          const std::size_t np = std::size_t(std::ptrdiff_t(p) + sgn * stride[d]);
          if (comp[np] < 0 && labels.data[np] == v) {
            comp[np] = id;
            queue.push_back(np);
          }
        }
      }
    }
  }
  if (comps.empty())
    throw std::invalid_argument("autoRig: no bone voxels: no label of the volume is a bone in the label table "
                                "(give a table with kind 'bone', or name the bones in the skeleton by hand)");

  // ---- keep components above the noise threshold; split labels holding several bones
  AutoRigResult result;
  AutoRigReport& report = result.report;
  result.table = table;
  std::map<int, std::vector<int>> compsOfLabel;
  for (int c = 0; c < int(comps.size()); ++c) compsOfLabel[comps[c].label].push_back(c);
  std::vector<int> boneOfComp(comps.size(), -1);
  std::vector<Bone> bones;
  for (auto& [label, list] : compsOfLabel) {
    std::sort(list.begin(), list.end(), [&](int a, int b) { return comps[a].count > comps[b].count; });
    const double threshold =
        std::max<double>(options.minComponentVoxels, options.noiseFraction * double(comps[list[0]].count));
    for (int c : list) {
      if (double(comps[c].count) < threshold) {
        ++report.noiseComponents;
        report.noiseVoxels += comps[c].count;
        continue;
      }
      Bone b;
      b.comp = c;
      b.sourceLabel = b.value = label;
      b.name = table.nameOf(label);
      b.count = comps[c].count;
      b.centroid = grid.indexToPhysical(comps[c].indexSum / double(comps[c].count));
      b.lo = comps[c].lo;
      b.hi = comps[c].hi;
      b.cut = comps[c].cut;
      boneOfComp[c] = int(bones.size());
      bones.push_back(b);
    }
  }
  for (const LabelInfo& l : table.labels) {
    if (l.kind != LabelKind::Bone) continue;
    bool present = false;
    for (const Bone& b : bones) present = present || b.sourceLabel == l.value;
    if (!present) report.missingBones.push_back(l.name);
  }
  if (bones.empty()) throw std::invalid_argument("autoRig: every bone component is smaller than the noise threshold");

  // Mid-sagittal plane: mean x of all bone voxels.
  double midX = 0, total = 0;
  for (const Bone& b : bones) {
    midX += b.centroid.x() * double(b.count);
    total += double(b.count);
  }
  midX /= total;

  int nextValue = maxLabel;
  for (const LabelInfo& l : table.labels) nextValue = std::max(nextValue, l.value);
  ++nextValue;
  std::map<int, std::vector<int>> bonesOfLabel;
  for (int b = 0; b < int(bones.size()); ++b) bonesOfLabel[bones[b].sourceLabel].push_back(b);
  std::vector<std::int32_t> newValueOfComp(comps.size(), 0);
  for (auto& [label, list] : bonesOfLabel) {
    if (list.size() < 2) continue;
    const std::string base = table.nameOf(label);
    const bool sided = list.size() == 2 &&
                       (bones[list[0]].centroid.x() - midX) * (bones[list[1]].centroid.x() - midX) < 0;
    for (std::size_t r = 0; r < list.size(); ++r) {  // list is largest first
      Bone& b = bones[list[r]];
      b.name = sided ? base + (b.centroid.x() > midX ? "_left" : "_right") : base + "_" + std::to_string(r + 1);
      b.value = r == 0 ? label : nextValue++;
      newValueOfComp[b.comp] = b.value;
      const LabelInfo info{b.value, b.name, LabelKind::Bone};
      auto it = std::find_if(result.table.labels.begin(), result.table.labels.end(),
                             [&](const LabelInfo& l) { return l.value == b.value; });
      if (it != result.table.labels.end()) *it = info;
      else result.table.labels.push_back(info);
    }
  }
  result.labels = labels;
  for (std::size_t p = 0; p < N; ++p)
    if (comp[p] >= 0 && newValueOfComp[comp[p]] > 0) result.labels.data[p] = newValueOfComp[comp[p]];

  // ---- boundary voxels (a 6-neighbour in another component)
  const int B = int(bones.size());
  parallelFor(std::size_t(B), [&](std::size_t b0, std::size_t b1) {
    for (std::size_t bi = b0; bi < b1; ++bi) {
      Bone& b = bones[bi];
      for (int k = b.lo[2]; k <= b.hi[2]; ++k)
        for (int j = b.lo[1]; j <= b.hi[1]; ++j)
          for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
            const std::size_t p = grid.linearIndex(i, j, k);
            if (comp[p] != b.comp) continue;
            const int ijk[3] = {i, j, k};
            bool edge = false;
            for (int d = 0; d < 3 && !edge; ++d)
              for (int sgn : {-1, 1}) {
                const int nd = ijk[d] + sgn;
                if (nd >= 0 && nd < grid.dims[d] && comp[std::size_t(std::ptrdiff_t(p) + sgn * stride[d])] != b.comp) {
                  edge = true;
                  break;
                }
              }
            if (edge) b.boundary.push_back(p);
          }
    }
  }, 1);

  // ---- distances between bone surfaces: stamp each bone's distance field (within the threshold)
  // into its padded bounding box, then read the other bones' boundary voxels there.
  const double gapLimit = std::max(options.maxGapMm, options.maxGapVoxels * hmax);
  const double thr = gapLimit + hmax;  // voxel-centre distance of surfaces gapLimit apart
  int rad[3];
  for (int d = 0; d < 3; ++d) rad[d] = int(std::floor(thr / h[d]));
  struct Offset { int di, dj, dk; float d; };
  std::vector<Offset> offsets;
  for (int dk = -rad[2]; dk <= rad[2]; ++dk)
    for (int dj = -rad[1]; dj <= rad[1]; ++dj)
      for (int di = -rad[0]; di <= rad[0]; ++di) {
        const double d = V3(di * h[0], dj * h[1], dk * h[2]).norm();
        if (d <= thr) offsets.push_back({di, dj, dk, float(d)});
      }
  std::vector<std::vector<Contact>> contacts(B);  // contacts[a]: other bones' voxels near a
  parallelFor(std::size_t(B), [&](std::size_t b0, std::size_t b1) {
    std::vector<float> dist;
    for (std::size_t ai = b0; ai < b1; ++ai) {
      const Bone& a = bones[ai];
      int lo[3], hi[3], dim[3];
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::max(0, a.lo[d] - rad[d]);
        hi[d] = std::min(grid.dims[d] - 1, a.hi[d] + rad[d]);
        dim[d] = hi[d] - lo[d] + 1;
      }
      std::vector<int> others;
      for (int o = 0; o < B; ++o) {
        if (o == int(ai)) continue;
        bool overlap = true;
        for (int d = 0; d < 3; ++d) overlap = overlap && bones[o].lo[d] <= hi[d] && bones[o].hi[d] >= lo[d];
        if (overlap) others.push_back(o);
      }
      if (others.empty()) continue;
      dist.assign(std::size_t(dim[0]) * dim[1] * dim[2], std::numeric_limits<float>::max());
      for (std::size_t p : a.boundary) {
        int i, j, k;
        coords(p, i, j, k);
        for (const Offset& o : offsets) {
          const int x = i + o.di - lo[0], y = j + o.dj - lo[1], z = k + o.dk - lo[2];
          if (x < 0 || y < 0 || z < 0 || x >= dim[0] || y >= dim[1] || z >= dim[2]) continue;
          float& t = dist[(std::size_t(z) * dim[1] + y) * dim[0] + x];
          t = std::min(t, o.d);
        }
      }
      for (int o : others) {
        Contact c;
        c.other = o;
        for (std::size_t p : bones[o].boundary) {
          int i, j, k;
          coords(p, i, j, k);
          if (i < lo[0] || j < lo[1] || k < lo[2] || i > hi[0] || j > hi[1] || k > hi[2]) continue;
          const float d = dist[(std::size_t(k - lo[2]) * dim[1] + (j - lo[1])) * dim[0] + (i - lo[0])];
          if (d <= thr) {
            c.near.emplace_back(p, d);
            c.dmin = std::min(c.dmin, d);
          }
        }
        if (!c.near.empty()) contacts[ai].push_back(std::move(c));
      }
    }
  }, 1);
  auto contactOf = [&](int a, int o) -> const Contact* {  // o's voxels near a
    for (const Contact& c : contacts[a])
      if (c.other == o) return &c;
    return nullptr;
  };

  // ---- fused groups
  UnionFind uf(B);
  for (int a = 0; a < B; ++a)
    for (const Contact& c : contacts[a])
      if (isPelvisLike(bones[a].name) && isPelvisLike(bones[c.other].name)) uf.unite(a, c.other);
  for (int a = 0; a < B; ++a)  // rib-like bones touching each other form one ribcage
    for (const Contact& c : contacts[a])
      if (isRibLike(bones[a].name) && isRibLike(bones[c.other].name)) uf.unite(a, c.other);
  {  // each ribcage group joins its closest vertebra
    std::map<int, std::pair<double, int>> best;  // rib group -> (gap, spine bone)
    for (int a = 0; a < B; ++a) {
      if (!isRibLike(bones[a].name)) continue;
      for (const Contact& c : contacts[a]) {
        if (!isSpineLike(bones[c.other].name)) continue;
        auto& e = best.try_emplace(uf.find(a), std::numeric_limits<double>::infinity(), -1).first->second;
        if (c.dmin < e.first) e = {c.dmin, c.other};
      }
    }
    for (const auto& [g, e] : best) uf.unite(g, e.second);
  }
  std::map<int, std::vector<int>> groupMembers;
  for (int a = 0; a < B; ++a) groupMembers[uf.find(a)].push_back(a);
  std::vector<int> groups;  // group id = representative bone
  for (const auto& [g, m] : groupMembers) groups.push_back(g);
  const int G = int(groups.size());
  std::vector<int> groupOf(B);
  for (int gi = 0; gi < G; ++gi)
    for (int a : groupMembers[groups[gi]]) groupOf[a] = gi;
  std::vector<std::size_t> groupVoxels(G, 0);
  std::vector<V3> groupCentroid(G, V3::Zero());
  std::vector<char> groupPelvis(G, 0);
  for (int a = 0; a < B; ++a) {
    const int g = groupOf[a];
    groupVoxels[g] += bones[a].count;
    groupCentroid[g] += bones[a].centroid * double(bones[a].count);
    groupPelvis[g] = groupPelvis[g] || isPelvisLike(bones[a].name);
  }
  for (int g = 0; g < G; ++g) groupCentroid[g] /= double(groupVoxels[g]);

  // ---- root: the largest pelvis group, else the largest group near the mid-sagittal plane
  int root = -1;
  for (int g = 0; g < G; ++g)
    if (groupPelvis[g] && (root < 0 || groupVoxels[g] > groupVoxels[root])) root = g;
  if (root < 0) {
    double xlo = 1e30, xhi = -1e30;
    for (const Bone& b : bones) {
      xlo = std::min(xlo, b.centroid.x());
      xhi = std::max(xhi, b.centroid.x());
    }
    const double band = std::max(0.1 * (xhi - xlo), 2 * hmax);
    for (int g = 0; g < G; ++g)
      if (std::abs(groupCentroid[g].x() - midX) <= band && (root < 0 || groupVoxels[g] > groupVoxels[root])) root = g;
    if (root < 0)
      root = int(std::max_element(groupVoxels.begin(), groupVoxels.end()) - groupVoxels.begin());
  }

  // ---- maximum spanning tree (smallest gap first, then the larger contact) from the root (Prim)
  struct Edge { double gap = std::numeric_limits<double>::infinity(); std::size_t size = 0; int child = -1, parent = -1; };
  auto better = [](const Edge& a, const Edge& b) { return a.gap < b.gap - 1e-9 || (std::abs(a.gap - b.gap) <= 1e-9 && a.size > b.size); };
  std::vector<char> inTree(G, 0);
  std::vector<int> order{root}, parentGroup(G, -1);
  std::vector<Edge> link(G);  // best edge from the tree to each group (child bone in the group)
  inTree[root] = 1;
  auto relax = [&](int g) {
    for (int a : groupMembers[groups[g]])
      for (const Contact& c : contacts[a]) {  // c.other's voxels near a (a in the tree)
        const int og = groupOf[c.other];
        if (inTree[og]) continue;
        Edge e{double(c.dmin), c.near.size(), c.other, a};
        if (better(e, link[og])) link[og] = e;
      }
  };
  relax(root);
  while (true) {
    int next = -1;
    for (int g = 0; g < G; ++g)
      if (!inTree[g] && link[g].child >= 0 && (next < 0 || better(link[g], link[next]))) next = g;
    if (next < 0) break;
    inTree[next] = 1;
    parentGroup[next] = groupOf[link[next].parent];
    order.push_back(next);
    relax(next);
  }

  // ---- names
  auto primaryBone = [&](int g) {  // the group's largest bone that is not a rib
    int best = -1;
    for (int a : groupMembers[groups[g]])
      if (best < 0 || (isRibLike(bones[best].name) && !isRibLike(bones[a].name)) ||
          (isRibLike(bones[best].name) == isRibLike(bones[a].name) && bones[a].count > bones[best].count))
        best = a;
    return best;
  };
  std::vector<std::string> jointName(G);
  std::set<std::string> used;
  for (int g : order) {
    std::string name;
    const int pb = primaryBone(g);
    if (g == root) name = groupPelvis[g] ? "pelvis" : (mapName(bones[pb].name).empty() ? bones[pb].name : mapName(bones[pb].name));
    else if (parentGroup[g] == root && groupPelvis[root] && isSpineLike(bones[pb].name)) name = "spine";
    else name = mapName(bones[pb].name).empty() ? bones[pb].name : mapName(bones[pb].name);
    std::string unique = name;
    for (int n = 2; used.count(unique); ++n) unique = name + "_" + std::to_string(n);
    used.insert(unique);
    jointName[g] = unique;
  }

  // ---- joint centres
  auto physical = [&](std::size_t p) {
    int i, j, k;
    coords(p, i, j, k);
    return grid.indexToPhysical(V3(i, j, k));
  };
  Skeleton& sk = result.skeleton;
  std::vector<int> jointOfGroup(G, -1);
  for (int g : order) {
    Joint joint;
    AutoRigReport::JointInfo info;
    joint.name = info.name = jointName[g];
    for (int a : groupMembers[groups[g]]) joint.labels.push_back(bones[a].value);
    std::sort(joint.labels.begin(), joint.labels.end());
    joint.labels.erase(std::unique(joint.labels.begin(), joint.labels.end()), joint.labels.end());
    if (g == root) {
      joint.center = groupCentroid[g];
      info.method = "root centroid";
    } else {
      const Edge& e = link[g];
      const int child = e.child, par = e.parent;
      joint.parent = jointOfGroup[parentGroup[g]];
      info.parent = jointName[parentGroup[g]];
      info.gapMm = std::max(0.0, e.gap - hmax);
      const Contact* cn = contactOf(par, child);  // child's voxels near the parent bone
      const Contact* pn = contactOf(child, par);  // parent's voxels near the child bone
      // Closest patches: voxels within one voxel of the closest distance, on both bones.
      auto patch = [&](const Contact* c) {
        V3 s = V3::Zero();
        int n = 0;
        if (c)
          for (const auto& [p, d] : c->near)
            if (d <= c->dmin + hmax) { s += physical(p); ++n; }
        return n ? V3(s / n) : V3(V3::Constant(std::numeric_limits<double>::quiet_NaN()));
      };
      const V3 cc = patch(cn), pc = patch(pn);
      V3 center = (cc.allFinite() && pc.allFinite()) ? V3(0.5 * (cc + pc)) : (cc.allFinite() ? cc : pc);
      info.method = "contact centroid";
      const BallHint hint = ballHint(bones[child].name);
      if (hint != BallHint::No && cn && cc.allFinite()) {
        // The head: the largest ball inscribed in the child that reaches its contact patch
        // (the neck and shaft are thinner), refined by a sphere fit to the surface around it.
        const Bone& cb = bones[child];
        const double reach = options.maxBallRadiusMm + hmax;
        std::vector<V3> surface;
        for (std::size_t p : cb.boundary) {
          const V3 x = physical(p);
          if ((x - cc).norm() <= 2 * reach) surface.push_back(x);
        }
        const V3 ci = grid.physicalToIndex(cc);
        int lo[3], hi[3];
        for (int d = 0; d < 3; ++d) {
          const int r = int(std::ceil(reach / h[d]));
          lo[d] = std::max(cb.lo[d], int(std::floor(ci[d])) - r);
          hi[d] = std::min(cb.hi[d], int(std::ceil(ci[d])) + r);
        }
        double bestRho = -1;
        std::vector<std::pair<double, V3>> balls;  // (inscribed radius, centre)
        for (int k = lo[2]; k <= hi[2]; ++k)
          for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i) {
              if (comp[grid.linearIndex(i, j, k)] != cb.comp) continue;
              const V3 x = grid.indexToPhysical(V3(i, j, k));
              const double toContact = (x - cc).norm();
              if (toContact > reach) continue;
              double rho = std::numeric_limits<double>::max();
              for (const V3& q : surface) rho = std::min(rho, (q - x).squaredNorm());
              rho = std::sqrt(rho);
              if (toContact > rho + 1.5 * hmax) continue;  // this ball does not reach the contact
              balls.emplace_back(rho, x);
              bestRho = std::max(bestRho, rho);
            }
        SphereFit f;
        if (bestRho > 0) {
          V3 c = V3::Zero();
          int n = 0;
          for (const auto& [rho, x] : balls)
            if (rho >= bestRho - 0.25 * h.minCoeff()) { c += x; ++n; }
          c /= n;
          std::vector<V3> pts;
          for (const V3& q : surface)
            if ((q - c).norm() <= bestRho + 1.5 * hmax) pts.push_back(q);
          f = fitSphere(pts, hmax);
          const double tolerance = std::max(0.5 * h.minCoeff(), 0.5 * hmax);
          if (!f.ok || f.rms > tolerance || (f.c - c).norm() > bestRho) {
            f.ok = bestRho + 0.5 * h.minCoeff() > 0;  // the fit failed: keep the inscribed ball
            f.c = c;
            f.r = bestRho + 0.5 * h.minCoeff();
            f.rms = 0;
          }
        }
        bool ok = f.ok && f.r >= options.minBallRadiusMm && f.r <= options.maxBallRadiusMm;
        if (ok && hint == BallHint::Unknown) {  // unknown bones: require a socket around the ball
          if (!pn || pn->near.size() < 6) ok = false;
          else {
            double s = 0, s2 = 0;
            for (const auto& [p, d] : pn->near) {
              const double r = (physical(p) - f.c).norm();
              s += r;
              s2 += r * r;
            }
            const double n = double(pn->near.size()), mean = s / n, sd = std::sqrt(std::max(0.0, s2 / n - mean * mean));
            ok = mean > f.r && sd <= 0.5 * hmax + 0.1 * f.r;
          }
        }
        if (ok) {
          center = f.c;
          info.method = f.rms > 0 ? "sphere fit" : "inscribed ball";
          info.radiusMm = f.r;
          info.fitRmsMm = f.rms;
        }
      }
      joint.center = center;
    }
    jointOfGroup[g] = int(sk.joints.size());
    sk.joints.push_back(joint);
    report.joints.push_back(info);
  }

  // ---- per-bone report
  for (int a = 0; a < B; ++a) {
    const Bone& b = bones[a];
    AutoRigReport::Bone r;
    r.name = b.name;
    r.label = b.value;
    r.sourceLabel = b.sourceLabel;
    r.voxels = b.count;
    r.cutByFieldOfView = b.cut;
    const int g = groupOf[a];
    if (inTree[g]) {
      r.joint = jointName[g];
      if (b.value != b.sourceLabel || bonesOfLabel[b.sourceLabel].size() > 1)
        r.note = "split from label " + std::to_string(b.sourceLabel);
    } else {
      r.note = "not within " + std::to_string(int(std::lround(gapLimit))) + " mm of the skeleton";
    }
    report.bones.push_back(r);
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace repose
