#include "animate_command.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "atomic_outputs.h"
#include "bvh.h"
#include "cli_options.h"
#include "console_progress.h"
#include "clip_retargeting.h"
#include "display_requirement.h"
#include "fidelity_report.h"
#include "mesh_binding.h"
#include "output_guard.h"
#include "pipeline_report.h"
#include "posed_writes.h"
#include "progress_line.h"
#include "pvd_series.h"
#include "relaxation_options.h"
#include "repose_pipeline.h"
#include "skeleton.h"
#include "volume_format_option.h"
#include "vtkReposeCorotationalRelax.h"

namespace repose {
namespace {

const char* kAnimateUsage =
    "usage: repose animate --case CASE_DIR --bvh FILE --out DIR [--map FILE] [--strict] [--frames START:STOP:STEP]\n"
    "                      [--skinning dqs|lbs] [--volumes] [--image FILE] [--mode direction|relative]\n"
    "                      [--reference-frame N] [--mesh FILE ...] [--no-root-motion] [--unit-mm MM]\n"
    "                      [--max-voxels N]\n"
    "  Retargets every selected frame of the clip onto the case's skeleton and writes the posed mesh and\n"
    "  surfaces per frame (DIR/frames/), DIR/animation.pvd (open it in ParaView) and DIR/frames.csv (per\n"
    "  frame: body volume ratio, posing time, with --volumes each label's voxel-count ratio, and with --relax\n"
    "  the FEM's time, Newton and CG iterations, inverted tets, continuation steps, the strained region's\n"
    "  nodes and Newton iterations, and the nodes pinched between bones).\n"
    "  First it prints the clip's units and which skeleton joints the clip drives, and warns about\n"
    "  recognised limb joints (left_knee, right_elbow, ...) that it does not drive and about joint names\n"
    "  the built-in map does not know: those only follow their parents. A clip that drives no joint of the\n"
    "  skeleton but its root is an error.\n"
    "  --map FILE        JSON {BVH joint: skeleton joint}. Default: the CMU clips (both conversions, LeftHip or\n"
    "                    LeftUpLeg names) onto the standard joint names: pelvis, spine, chest, vertebra_L4 ...,\n"
    "                    neck, head, left_/right_ hip, knee, ankle, shoulder, elbow, wrist, clavicle, scapula; the\n"
    "                    vertebrae share the clip's spine and neck rotations by spinal level\n"
    "  --strict          a recognised limb joint that the clip does not drive, or (without --map) a joint name\n"
    "                    the built-in map does not know, is an error, not a warning\n"
    "  --frames A:B:S    frames A (inclusive) to B (exclusive) every S (default: all)\n"
    "  --volumes         also write a posed label volume per frame (DIR/frames/labels_NNNNN.nii.gz)\n"
    "  --format EXT      the format of the frames' volumes (.nii.gz, .nii, .nrrd, .mha, .mhd, .vti); with .vti the\n"
    "                    label volume and CT of each frame are parts of animation.pvd too (ParaView); seg.nrrd\n"
    "                    writes each frame's labels as a 3D Slicer segmentation (its CT as .nrrd)\n"
    "  --image FILE      also pose this CT/MRI (on the case's label grid) per frame (DIR/frames/image_NNNNN.*); a\n"
    "                    folder is read as a DICOM CT series (--series-uid UID when it holds several) and each\n"
    "                    frame's CT written as one (DIR/frames/image_NNNNN/)\n"
    "  --mode            direction (default): each limb bone points where the BVH bone points, the trunk and\n"
    "                    head bend as the clip's bend from its rest pose; relative: each joint's rotation\n"
    "                    relative to --reference-frame (default 0), taken to be the scan's rest pose\n"
    "  --no-root-motion  keep the pelvis where it is in the scan: the body moves its joints but does not travel\n"
    "                    (a walk on the spot). Default: the body travels by the clip's root displacement from\n"
    "                    the reference frame, converted by the clip's units\n"
    "  --unit-mm MM      millimetres per BVH unit. Default: inferred from the clip's leg length against an\n"
    "                    adult's (CMU clips 56.44, centimetres 10, inches 25.4, metres 1000) and printed\n"
    "  --max-voxels N    largest posed volume of a frame (default 512M; k, M, G suffixes): a larger one stops\n"
    "                    with an error. Volumes stay on the rest grid's lattice; a body that travelled away\n"
    "                    gets a grid cropped to it\n"
    "  --relax           corotational FEM relaxation of every frame (see repose pose --help)\n"
    "  --relax-start S   previous (default): each frame's FEM starts from the frame before's correction\n"
    "                    (fewer Newton steps, coherent frames); skinned: every frame from its skinned pose alone\n"
    "  --mesh FILE       also pose this mesh per frame (see repose pose --help; repeatable): DIR/frames/<name>_NNNNN.vtp,\n"
    "                    one series per mesh in animation.pvd\n"
    "  --compare M,...   per frame and method (lbs, dqs, lbs+fem, dqs+fem): fidelity.csv and fidelity.png\n";

/// The frames --frames selects: start (inclusive) to stop (exclusive) every step.
struct FrameRange {
  int start = 0, stop = -1, step = 1;
};

/// --frames START:STOP:STEP (each part optional) of a clip of frameCount frames; UsageError when it
/// selects no frame.
FrameRange parseFrames(const std::string& text, int frameCount) {
  FrameRange r;
  r.stop = frameCount;
  if (text.empty()) return r;
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string p; std::getline(in, p, ':');) parts.push_back(p);
  if (parts.empty() || parts.size() > 3) throw UsageError("--frames needs START:STOP:STEP, not '" + text + "'");
  auto number = [&](const std::string& p, int fallback) {
    if (p.empty()) return fallback;
    char* end = nullptr;
    const long v = std::strtol(p.c_str(), &end, 10);
    if (*end != '\0') throw UsageError("--frames needs whole numbers, not '" + text + "'");
    return static_cast<int>(v);
  };
  r.start = number(parts[0], 0);
  if (parts.size() > 1) r.stop = std::min(number(parts[1], frameCount), frameCount);
  if (parts.size() > 2) r.step = number(parts[2], 1);
  if (r.start < 0 || r.start >= frameCount || r.step < 1 || r.stop <= r.start)
    throw UsageError("--frames " + text + " selects no frame of a clip with " + std::to_string(frameCount) + " frames");
  return r;
}

/// Voxels per non-zero label value.
std::map<int, long> labelCounts(vtkImageData* labels) {
  std::map<int, long> counts;
  vtkDataArray* a = labels->GetPointData()->GetScalars();
  const vtkIdType n = a->GetNumberOfTuples();
  if (auto* ints = vtkIntArray::SafeDownCast(a)) {
    const int* p = ints->GetPointer(0);
    for (vtkIdType i = 0; i < n; ++i)
      if (p[i] != 0) ++counts[p[i]];
  } else {
    for (vtkIdType i = 0; i < n; ++i)
      if (a->GetTuple1(i) != 0) ++counts[static_cast<int>(a->GetTuple1(i))];
  }
  return counts;
}

/// "512M", "2G", "300k", "1e9" -> a voxel count (k, M, G: thousands, millions, billions).
double parseVoxelCount(const std::string& text) {
  char* end = nullptr;
  double v = std::strtod(text.c_str(), &end);
  const std::string suffix = end ? std::string(end) : std::string();
  if (suffix == "k" || suffix == "K") v *= 1e3;
  else if (suffix == "M") v *= 1e6;
  else if (suffix == "G") v *= 1e9;
  else if (!suffix.empty()) v = -1;
  if (text.empty() || !std::isfinite(v) || v < 1)
    throw UsageError("--max-voxels needs a voxel count such as 512M, 2G or 300000000, not '" + text + "'");
  return v;
}

/// frames.csv: one row per frame with the body's and each label's volume ratio, the posing time, the
/// relaxation's figures (with --relax) and the quality figures.
class FramesTable {
 public:
  FramesTable(const std::map<int, long>& restLabelCounts, bool relaxing, bool volumes)
      : restCounts_(restLabelCounts), relaxing_(relaxing), volumes_(volumes) {
    csv_ << "frame,time_s,body_volume_ratio,posing_ms";
    for (const auto& [label, count] : restCounts_) csv_ << ",label_" << label << "_ratio";
    if (relaxing_)
      csv_ << ",relax_s,newton_iterations,cg_iterations,inverted_tets,continuation_steps,warm_start,"
              "strained_region_nodes,strained_region_newton_iterations,pinched_nodes";
    csv_ << ",mesh_inverted_tets,max_stretch,stretched_ml" << (volumes_ ? ",contested_bone_voxels" : "") << "\n";
  }

  /// The row of frame `f`; `labels` is its posed label volume (null without --volumes).
  void add(Pipeline& pipeline, int f, double time, double bodyRatio, double posingSeconds, vtkImageData* labels,
           const DeformationStats& stats) {
    csv_ << f << "," << time << "," << bodyRatio << "," << posingSeconds * 1e3;
    if (labels) {
      const auto counts = labelCounts(labels);
      for (const auto& [label, count] : restCounts_) {
        auto it = counts.find(label);
        csv_ << "," << double(it == counts.end() ? 0 : it->second) / double(count);
      }
    }
    if (vtkReposeCorotationalRelax* relax = relaxing_ ? pipeline.relaxation() : nullptr)
      csv_ << "," << relax->GetLastRelaxTime() << "," << relax->GetNewtonIterations() << ","
           << relax->GetCGIterations() << "," << relax->GetInvertedAfter() << "," << relax->GetContinuationSteps()
           << "," << int(relax->GetWarmStarted()) << "," << relax->GetStrainedRegionNodes() << ","
           << relax->GetStrainedRegionNewtonIterations() << "," << relax->GetPinchedNodes();
    csv_ << "," << stats.invertedTets << "," << stats.maxStretch << "," << stats.stretchedVolumeMm3 / 1000.0;
    if (volumes_) csv_ << "," << pipeline.posedLabelStats().contestedBoneVoxels;
    csv_ << "\n";
  }

  std::string text() const { return csv_.str(); }

 private:
  std::map<int, long> restCounts_;
  bool relaxing_, volumes_;
  std::ostringstream csv_;
};

/// Each frame's files in frames/ (mesh, surfaces, the posed meshes, the volumes) and their entries
/// in animation.pvd: part 0 the mesh, 1 the surfaces, then the meshes, then the labels and the CT
/// when they are .vti (ParaView reads no other volume format from a .pvd).
class FrameFiles {
 public:
  FrameFiles(Pipeline& pipeline, AtomicOutputs& out, const MeshPoser* meshes, std::string volumeExt,
             std::string imageExt)
      : pipeline_(pipeline), out_(out), meshes_(meshes), volumeExt_(std::move(volumeExt)), imageExt_(std::move(imageExt)),
        volumePart_(2 + int(meshes ? meshes->meshes().size() : 0)) {}

  void write(int f, double time, vtkUnstructuredGrid* mesh, vtkPolyData* surfaces, vtkImageData* labels,
             vtkImageData* image) {
    add(time, 0, numbered("frames/mesh_", f, ".vtu"), [&](const std::string& path) { writeMesh(mesh, path); });
    add(time, 1, numbered("frames/surfaces_", f, ".vtp"),
        [&](const std::string& path) { writeSurfaces(surfaces, path); });
    for (std::size_t i = 0; meshes_ && i < meshes_->meshes().size(); ++i) {
      const std::string stem = std::filesystem::path(meshes_->meshes()[i].path).stem().string();
      add(time, int(2 + i), numbered("frames/" + stem + "_", f, ".vtp"),
          [&](const std::string& path) { writeSurfaces(meshes_->pose(i, mesh), path); });
    }
    const bool inPvd = volumeExt_ == ".vti";
    if (labels)
      add(time, inPvd ? volumePart_ : -1, numbered("frames/labels_", f, volumeExt_),
          [&](const std::string& path) { writeLabelVolume(pipeline_, labels, path); });
    if (image)
      add(time, inPvd ? volumePart_ + 1 : -1, numbered("frames/image_", f, imageExt_),
          [&](const std::string& path) { writeImage(image, path); });
  }

  const std::vector<PvdEntry>& entries() const { return entries_; }

 private:
  static std::string numbered(const std::string& prefix, int f, const std::string& ext) {
    char digits[16];
    std::snprintf(digits, sizeof(digits), "%05d", f);
    return prefix + digits + ext;
  }
  /// Writes `name` through the staged outputs; part < 0: not listed in animation.pvd.
  template <class Write>
  void add(double time, int part, const std::string& name, Write write) {
    write(out_.stage(name));
    if (part >= 0) entries_.push_back({time, part, name});
  }

  Pipeline& pipeline_;  // the case's label table, for label formats that carry it
  AtomicOutputs& out_;
  const MeshPoser* meshes_;
  std::string volumeExt_, imageExt_;
  int volumePart_;
  std::vector<PvdEntry> entries_;
};

/// The posed volumes of the frame; a volume too large for --max-voxels gets the ways out.
void posedVolumesOf(Pipeline& pipeline, bool volumes, int f, const std::string& bvhPath, vtkImageData*& labels,
                    vtkImageData*& image) {
  try {
    labels = volumes ? pipeline.posedLabels() : nullptr;
    image = pipeline.posedImage();
  } catch (const std::runtime_error& e) {
    const bool tooLarge = std::string(e.what()).find("posed volume would have") != std::string::npos;
    throw std::runtime_error(bvhPath + ": frame " + std::to_string(f) + ": " + e.what() +
                             (tooLarge ? "; keep the root in place (--no-root-motion), check the clip's units "
                                         "(--unit-mm) or raise --max-voxels"
                                       : ""));
  }
}

/// Posing times and the largest posed volume over the frames, and the frames the quality check flagged.
struct AnimationSummary {
  int written = 0;
  double totalPosing = 0, worstPosing = 0, largestVolume = 0;
  int largestDims[3] = {0, 0, 0};
  std::vector<std::pair<int, PoseQuality>> warned;

  void addFrame(double posingSeconds, std::initializer_list<vtkImageData*> frameVolumes) {
    ++written;
    totalPosing += posingSeconds;
    worstPosing = std::max(worstPosing, posingSeconds);
    for (vtkImageData* volume : frameVolumes)
      if (volume && double(volume->GetNumberOfPoints()) > largestVolume) {
        largestVolume = double(volume->GetNumberOfPoints());
        volume->GetDimensions(largestDims);
      }
  }

  void print(const std::string& bvhPath, const std::string& outDir, bool volumes) const {
    std::cout << "animate: " << written << " frames of " << bvhPath << " written to " << outDir << " (posing "
              << std::fixed << std::setprecision(1) << 1e3 * totalPosing / std::max(written, 1) << " ms mean, "
              << 1e3 * worstPosing << " ms worst per frame" << (volumes ? ", with the label volume" : "") << ")\n";
    if (largestVolume > 0)
      std::cout << "animate: largest posed volume " << largestDims[0] << " x " << largestDims[1] << " x "
                << largestDims[2] << " = " << std::setprecision(3) << largestVolume / 1e6 << " M voxels\n";
    // The frames that went wrong, the first few in full (every frame's figures are in frames.csv).
    std::cout << "animate: quality flagged " << warned.size() << " of " << written << " frames (frames.csv: "
              << "mesh_inverted_tets, max_stretch, stretched_ml" << (volumes ? ", contested_bone_voxels" : "") << ")\n";
    const std::size_t shown = std::min<std::size_t>(warned.size(), 3);
    for (std::size_t i = 0; i < shown; ++i)
      for (const std::string& w : warned[i].second.warnings)
        std::cerr << "warning: frame " << warned[i].first << ": " << w << "\n";
    if (warned.size() > shown) std::cerr << "warning: ... and " << warned.size() - shown << " more frames\n";
  }
};

}  // namespace

int runAnimateCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first,
                  {"case", "bvh", "out", "map", "frames", "skinning", "mode", "reference-frame", "unit-mm",
                   "max-voxels", "image", "series-uid", "relax-iterations", "relax-model", "relax-volume", "relax-continuation",
                   "relax-strained-region", "poisson", "relax-start", "compare", "mesh", "format"},
                  {"volumes", "no-root-motion", "relax", "strict"});
  if (o.help) return std::cout << kAnimateUsage, 0;
  if (o.has("compare")) requireDisplay(argc, argv, "fidelity.png");
  const std::string caseDir = o.require("case");
  const std::string bvhPath = o.require("bvh");
  const std::string outDir = o.require("out");
  refuseOutputsOverInputs(outDir, {"frames", "animation.pvd", "frames.csv", "fidelity.csv", "fidelity.png"},
                                  {inputFiles(o, {"bvh", "map", "image"}), {caseDir}});
  const bool warmStart = relaxationWarmStart(o);
  const double maxVoxels = parseVoxelCount(o.get("max-voxels", "512M"));
  if (o.has("unit-mm") && !(o.number("unit-mm", 0) > 0)) throw UsageError("--unit-mm needs a positive number of millimetres");
  Pipeline pipeline;
  pipeline.setProgress(throttledConsoleProgress("animate: "));
  pipeline.loadCase(caseDir);
  pipeline.setMaxPosedVoxels(maxVoxels);
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  pipeline.setRelaxationWarmStart(warmStart);
  const RelaxationChoice relaxation = applyRelaxation(pipeline, o);
  const Skeleton skeleton = parseSkeletonJson(pipeline.skeletonJson());

  BvhMotion motion;
  try {
    motion = readBvhFile(bvhPath);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  const std::unique_ptr<BvhRetargeter> retargeter = retargetClip(o, skeleton, motion, bvhPath);
  const FrameRange range = parseFrames(o.get("frames"), motion.frameCount);
  const std::size_t frameCount = std::size_t(std::max(0, (range.stop - range.start + range.step - 1) / range.step));
  const auto animateStart = std::chrono::steady_clock::now();
  const bool volumes = o.has("volumes");
  FidelityReport fidelity;
  fidelity.methods = parseCompare(o);
  std::string imageExt;
  if (o.has("image")) {
    pipeline.setRestImage(readIntensityImage(o.get("image"), o.get("series-uid")), o.get("image"));
    imageExt = imageExtension(o.get("image"));
  }
  if (o.has("format") && !o.has("volumes") && !o.has("image"))
    throw UsageError("--format sets the format of the frames' volumes: it needs --volumes or --image");
  const std::string volumeExt = o.has("format") ? normalizedLabelFormat(o.get("format")) : ".nii.gz";
  if (o.has("format")) imageExt = imageFormatBeside(volumeExt);

  std::unique_ptr<MeshPoser> meshes = bindMeshes(pipeline, o, caseDir);
  AtomicOutputs out(outDir);
  makeDirectories(out.stage("frames"));
  if (volumes) writeLabelTables(pipeline, out, "frames/labels");
  const double restVolume = pipeline.restMeshVolume();
  FramesTable table(volumes ? labelCounts(pipeline.restLabels()) : std::map<int, long>(), o.has("relax"), volumes);
  FrameFiles files(pipeline, out, meshes.get(), volumeExt, imageExt);
  AnimationSummary summary;
  for (int f = range.start; f < range.stop; f += range.step) {
    pipeline.setPose(retargeter->pose(f));
    if (!fidelity.methods.empty())
      fidelity.addFrame(pipeline, f, o.get("skinning", "dqs"), relaxation.enabled, relaxation.poisson,
                        relaxation.iterations);
    // Posing time of the frame as the user asked for it (the comparison's methods are not counted).
    const auto t0 = std::chrono::steady_clock::now();
    vtkUnstructuredGrid* mesh = pipeline.posedMesh();
    vtkPolyData* surfaces = pipeline.posedSurfaces();
    vtkImageData *labels = nullptr, *image = nullptr;
    posedVolumesOf(pipeline, volumes, f, bvhPath, labels, image);
    const double posing = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    summary.addFrame(posing, {labels, image});
    const double time = f * motion.frameTime;
    files.write(f, time, mesh, surfaces, labels, image);
    const DeformationStats stats = pipeline.posedStats();
    table.add(pipeline, f, time, pipeline.posedMeshVolume() / restVolume, posing, labels, stats);
    PoseQuality quality = poseQualityOf(pipeline, stats);
    if (!quality.warnings.empty()) summary.warned.emplace_back(f, std::move(quality));
    if (summary.written % 10 == 0)
      std::cout << "animate: "
                << progressLine(std::size_t(summary.written), frameCount,
                                std::chrono::duration<double>(std::chrono::steady_clock::now() - animateStart).count(),
                                "frames")
                << std::endl;
  }
  writeTextFile(out.stage("animation.pvd"), pvdText(files.entries()));
  writeTextFile(out.stage("frames.csv"), table.text());
  if (!fidelity.methods.empty()) fidelity.write(out);
  out.commit();
  summary.print(bvhPath, outDir, volumes);
  return 0;
}

}  // namespace repose
