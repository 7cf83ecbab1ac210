#include "auto_rig.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "bone_components.h"
#include "bone_contacts.h"
#include "bone_fragments.h"
#include "joint_centers.h"
#include "label_table_fit.h"
#include "rig_tree.h"

namespace repose {

namespace {

void validate(const LabelVolume& labels, const AutoRigOptions& options) {
  const ImageGrid& grid = labels.grid;
  if (grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0)
    throw std::invalid_argument("autoRig: the label volume is empty");
  if (labels.data.size() != grid.voxelCount())
    throw std::invalid_argument("autoRig: the label volume has " + std::to_string(labels.data.size()) +
                                " values for " + std::to_string(grid.voxelCount()) + " voxels");
  if (!(grid.spacing.array() > 0).all()) throw std::invalid_argument("autoRig: the spacing must be positive");
  if (!(options.maxGapMm >= 0) || !(options.maxGapVoxels >= 0) || !(options.minBoneFraction >= 0) ||
      options.minBoneFraction > 1 || !(options.maxFragmentDistanceMm >= 0) || !(options.maxAnatomicGapMm >= 0))
    throw std::invalid_argument("autoRig: gaps and distances must be >= 0 and the bone fraction within [0, 1]");
}

void reportBones(const RigBones& rb, const RigTree& tree, const LabelTable& table, AutoRigReport& report) {
  std::map<int, int> bonesOfLabel;
  for (const RigBone& b : rb.bones) ++bonesOfLabel[b.sourceLabel];
  for (int a = 0; a < int(rb.bones.size()); ++a) {
    const RigBone& b = rb.bones[a];
    AutoRigReport::Bone r;
    r.name = b.name;
    r.label = b.value;
    r.sourceLabel = b.sourceLabel;
    r.voxels = b.voxels;
    r.cutByFieldOfView = b.cut;
    const int j = tree.jointOfBone[a];
    if (j >= 0) r.joint = tree.joints[j].name;
    r.note = tree.note[a];
    if (j >= 0 && bonesOfLabel[b.sourceLabel] > 1)
      r.note = "split from label " + std::to_string(b.sourceLabel) +
               (rb.components[b.comp].halved ? " at the mid-sagittal plane (both sides touch)" : "") +
               (r.note.empty() ? "" : "; " + r.note);
    report.bones.push_back(r);
  }
  for (const LabelInfo& l : table.labels) {
    if (l.kind != LabelKind::Bone) continue;
    if (!bonesOfLabel.count(l.value)) report.missingBones.push_back(l.name);
  }
}

void reportFragments(const RigBones& rb, const LabelTable& table, AutoRigReport& report) {
  for (const BoneFragment& f : rb.fragments) {
    AutoRigReport::Fragment r;
    r.label = table.nameOf(f.label);
    r.sourceLabel = f.label;
    r.voxels = f.voxels;
    r.why = f.why;
    if (f.bone >= 0) {
      r.bone = rb.bones[f.bone].name;
      r.value = rb.bones[f.bone].value;
      ++report.fragmentsReassigned;
      report.fragmentVoxelsReassigned += f.voxels;
    } else {
      r.value = rb.unassignedValue;
      ++report.noiseComponents;
      report.noiseVoxels += f.voxels;
    }
    report.fragments.push_back(r);
  }
  std::stable_sort(report.fragments.begin(), report.fragments.end(),
                   [](const auto& a, const auto& b) { return a.voxels > b.voxels; });
}

}  // namespace

std::string AutoRigReport::text() const {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  if (!tableSource.empty()) out << "label table: " << tableSource << "\n";
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
  out << "fragments: " << fragmentsReassigned << " (" << fragmentVoxelsReassigned << " voxels) given to bones, "
      << noiseComponents << " (" << noiseVoxels << " voxels) left as soft tissue\n";
  // The 30 largest fragments on a line each; the rest summed per label, bone and kind of reason.
  std::map<std::tuple<std::string, int, std::string, std::string>, std::pair<std::size_t, std::size_t>> rest;
  for (std::size_t i = 0; i < fragments.size(); ++i) {
    const Fragment& f = fragments[i];
    const std::string to = f.bone.empty() ? "soft tissue (label " + std::to_string(f.value) + ")"
                                          : f.bone + " (label " + std::to_string(f.value) + ")";
    if (i < 30) {
      out << "  " << f.label << " (label " << f.sourceLabel << "), " << f.voxels << " voxel" << (f.voxels == 1 ? "" : "s")
          << " -> " << to << ": " << f.why << "\n";
    } else {
      auto& s = rest[{f.label, f.sourceLabel, to, f.why.substr(0, f.why.find_first_of(",:"))}];
      ++s.first;
      s.second += f.voxels;
    }
  }
  for (const auto& [key, s] : rest)
    out << "  " << std::get<0>(key) << " (label " << std::get<1>(key) << "), " << s.first << " smaller fragments ("
        << s.second << " voxels) -> " << std::get<2>(key) << ": " << std::get<3>(key) << "\n";
  return out.str();
}

AutoRigResult autoRig(const LabelVolume& labels, const LabelTable& table, const AutoRigOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(labels, options);
  const ImageGrid& grid = labels.grid;
  if (options.checkTable) {
    const LabelTableFit fit = checkLabelTableFit(labels, table);
    if (!fit.fits())
      throw std::invalid_argument((table.source.empty() ? std::string("the label table") : table.source) +
                                  " does not match the label volume: " + fit.problem() +
                                  " (give the volume's own label table)");
  }
  RigBones rb;
  findBoneComponents(labels, table, rb);
  chooseBones(grid, table, options, rb);
  findBoneBoundaries(grid, rb);
  assignFragments(labels, options, rb);
  if (!rb.fragments.empty()) findBoneBoundaries(grid, rb);  // with the fragments they received

  const double hmax = grid.spacing.maxCoeff();
  const double gapLimit = std::max(options.maxGapMm, options.maxGapVoxels * hmax);
  const double contactMm = gapLimit + hmax;  // voxel-centre distance of surfaces gapLimit apart
  const auto contacts = findBoneContacts(grid, rb, contactMm);
  const RigTree tree = planSkeleton(grid, rb, contacts, contactMm, options);
  const std::vector<JointCenter> centers = findJointCenters(grid, rb, contacts, tree, options);

  AutoRigResult result;
  AutoRigReport& report = result.report;
  report.tableSource = table.source;
  for (std::size_t i = 0; i < tree.joints.size(); ++i) {
    const PlannedJoint& pj = tree.joints[i];
    Joint joint;
    joint.name = pj.name;
    joint.parent = pj.parent;
    joint.center = centers[i].center;
    for (int a : pj.bones) joint.labels.push_back(rb.bones[a].value);
    std::sort(joint.labels.begin(), joint.labels.end());
    joint.labels.erase(std::unique(joint.labels.begin(), joint.labels.end()), joint.labels.end());
    result.skeleton.joints.push_back(joint);
    AutoRigReport::JointInfo info;
    info.name = pj.name;
    info.parent = pj.parent >= 0 ? tree.joints[pj.parent].name : "";
    info.method = centers[i].method;
    info.gapMm = pj.parent >= 0 ? std::max(0.0, pj.gapMm - hmax) : 0.0;
    info.radiusMm = centers[i].radiusMm;
    info.fitRmsMm = centers[i].fitRmsMm;
    report.joints.push_back(info);
  }
  reportBones(rb, tree, table, report);
  reportFragments(rb, table, report);
  result.labels = relabelBones(labels, rb);
  result.table = rb.table;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace repose
