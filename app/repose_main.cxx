// The `repose` command line: demo, phantom, prepare, pose.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <cstdlib>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkOutputWindow.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "vtkReposeAutoRig.h"
#include "vtkReposePhantomSource.h"

#include "atomic_outputs.h"
#include "interrupt_cleanup.h"
#include "output_guard.h"
#include "batch_command.h"
#include "console_progress.h"
#include "deformation_stats.h"
#include "fidelity_plot.h"
#include "label_table.h"
#include "label_table_fit.h"
#include "mesh_io.h"
#include "mesh_posing.h"
#include "pose_quality.h"
#include "progress_line.h"
#include "ReposeImageConversion.h"
#include "vdb_volume_writer.h"
#include "repose_version.h"
#include "bvh.h"
#include "pvd_series.h"
#include "retarget.h"
#include "pose.h"
#include "render_snapshot.h"
#include "repose_pipeline.h"
#include "vtkReposeCorotationalRelax.h"
#include "skeleton.h"
#include "voxelize_command.h"

namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `--name value` options and `--flag` switches of one command.
class Options {
public:
  Options(int argc, char** argv, int first, const std::set<std::string>& valued, const std::set<std::string>& flags) {
    for (int i = first; i < argc; ++i) {
      std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        help = true;
        continue;
      }
      if (a.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + a + "'");
      std::string name = a.substr(2), value;
      const auto eq = name.find('=');
      if (eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
      }
      if (flags.count(name)) {
        values_[name] = "1";
      } else if (valued.count(name)) {
        if (eq == std::string::npos) {
          if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
          value = argv[++i];
        }
        values_[name] = value;
        lists_[name].push_back(value);
      } else {
        throw UsageError("unknown option --" + name);
      }
    }
  }
  bool has(const std::string& n) const { return values_.count(n) != 0; }
  std::string get(const std::string& n, const std::string& fallback = "") const {
    auto it = values_.find(n);
    return it == values_.end() ? fallback : it->second;
  }
  std::string require(const std::string& n) const {
    if (!has(n) || get(n).empty()) throw UsageError("missing required option --" + n);
    return get(n);
  }
  double number(const std::string& n, double fallback) const {
    if (!has(n)) return fallback;
    char* end = nullptr;
    const std::string v = get(n);
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(x)) throw UsageError("--" + n + " needs a number, not '" + v + "'");
    return x;
  }
  /// Every value of a repeatable option, in order.
  std::vector<std::string> all(const std::string& n) const {
    auto it = lists_.find(n);
    return it == lists_.end() ? std::vector<std::string>() : it->second;
  }
  bool help = false;

private:
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> lists_;
};

const char* kMainUsage =
    "usage: repose COMMAND [OPTIONS]\n"
    "Repose a segmented CT/MRI scan: tet mesh, harmonic bone weights, skinning, posed volume.\n\n"
    "commands:\n"
    "  demo      built-in phantom -> prepare -> pose; writes every output and render.png\n"
    "  phantom   write the built-in phantom's labels.nii.gz and skeleton.json\n"
    "  prepare   mesh a label volume, compute bone weights and bind surfaces (once per scan)\n"
    "  pose      pose a prepared case: posed label volume, mesh and surfaces\n"
    "  animate   drive a prepared case with a BVH motion clip: a ParaView time series\n"
    "  rig       find the joints from the bone labels and write an editable skeleton.json\n"
    "  voxelize  surface meshes (skin, bones, tissues) -> a label volume and its label table\n"
    "  batch     many subjects x poses and BVH frames from a manifest, on Dask (a local or a remote cluster)\n\n"
    "Run 'repose COMMAND --help' for the options of a command; 'repose --version' prints the version.\n";

const char* kDemoUsage =
    "usage: repose demo [--out DIR] [--size tiny|small|medium|large] [--skinning dqs|lbs] [--no-render]\n"
    "  Builds the phantom, prepares it and poses it (left hip flexed 60 deg, left knee 45 deg,\n"
    "  right shoulder abducted 80 deg, right elbow 90 deg). Writes into DIR (default ./repose-demo):\n"
    "  rest_labels.nii.gz, skeleton.json, pose.json, case/, posed_labels.nii.gz, posed_mesh.vtu,\n"
    "  posed_surfaces.vtp, rest_surfaces.vtp and render.png, and prints the time of each stage.\n"
    "  --size       phantom size (default small)\n"
    "  --no-render  skip render.png (it needs an X display; without one, repose runs itself under xvfb-run)\n";

const char* kPhantomUsage =
    "usage: repose phantom --out DIR [--size tiny|small|medium|large] [--rest-pose apart|contact]\n"
    "  Writes DIR/labels.nii.gz, DIR/skeleton.json and DIR/labels.tsv (label table).\n"
    "  --rest-pose apart    arms and thighs clear of each other (default)\n"
    "  --rest-pose contact  as real scans are taken: arms against the torso, hands against the thighs,\n"
    "                       thighs touching, with no background between them\n";

const char* kRigUsage =
    "usage: repose rig --labels FILE [--label-table FILE] --out skeleton.json [--max-gap MM]\n"
    "  Finds the joints from the bone labels and writes an editable skeleton.json, rooted at the pelvis.\n"
    "  Ball joints by sphere fits to the femoral and humeral heads, others where adjacent bones come closest.\n"
    "  A label holding both sides (femur) is split (femur_left, femur_right). Smaller pieces of a label\n"
    "  (under 25 % of its largest piece or 0.5 ml, or more than one per side) are never joints: each goes to\n"
    "  its own bone when that touches it or lies within 20 mm on its side of the midline, else to a bone it\n"
    "  touches, else to the nearest bone on its side within 20 mm, else it is left as soft tissue (label\n"
    "  unassigned_bone_fragments); the report says where each went. Parents follow anatomy: skull on the\n"
    "  cervical spine, patella with its femur, ribs and sternum with the spine, clavicle - scapula - humerus\n"
    "  on each side. Joint names come from a fixed vocabulary whatever the table calls the bones: pelvis,\n"
    "  spine, chest, neck, head, jaw, vertebra_L4, left_/right_ clavicle, scapula, shoulder, elbow, wrist,\n"
    "  hip, knee, ankle. When labels were split or pieces moved, the relabelled volume and its table are\n"
    "  written beside the skeleton (labels_rigged.nii.gz, labels_rigged.tsv).\n"
    "  --label-table FILE  value<TAB>name[<TAB>bone|soft|background] lines, or a 3D Slicer colour table\n"
    "                      (.ctbl/.txt: value name R G B A). Default: the table beside the labels (NAME.tsv,\n"
    "                      NAME.ctbl, NAME_ColorTable.ctbl, NAME.txt unless it holds no table, labels.tsv for\n"
    "                      NAME.nii.gz), else TotalSegmentator's class names. A table whose bone names\n"
    "                      contradict where the bones lie (the wrong table) is an error\n"
    "  --max-gap MM        largest gap between bones that still makes a joint (default 6)\n";

const char* kPrepareUsage =
    "usage: repose prepare --labels FILE --skeleton FILE|auto [--image CT_FILE] --out CASE_DIR [options]\n"
    "  Meshes the body with TetGen, solves Laplace's equation for the bone weights and binds the skin\n"
    "  and bone surfaces to the mesh. CASE_DIR then holds mesh.vtu, surfaces.vtp, skeleton.json,\n"
    "  labels.<ext>, labels.tsv (the label table) and manifest.json (ParaView opens the .vtu/.vtp as they are).\n"
    "  --skeleton auto         find the skeleton from the bone labels (see 'repose rig')\n"
    "  --label-table FILE      label names and kinds (TSV or 3D Slicer colour table); default: the table beside\n"
    "                          the labels, else TotalSegmentator's names (see 'repose rig --help')\n"
    "  --image FILE            CT on the label grid: the body is the labels united with CT above the threshold\n"
    "  --body-threshold HU     default -500\n"
    "  --max-tets N            tet budget (default 3000000, the paper's scale): the body is meshed on the finest\n"
    "                          voxel size, not finer than the labels', whose mesh fits it; 0 = the label spacing\n"
    "  --mesh-spacing MM       mesh the body on this voxel size instead (overrides --max-tets); coarser = fewer tets\n"
    "  --quality RATIO         TetGen radius-edge bound (default 2.0)\n"
    "  --influences K          bone weights kept per node (default 4)\n"
    "  --surface-reduction F   fraction of surface triangles removed by decimation (default 0)\n"
    "  --contact-separation on|off  cut apart body parts that touch in the scan (an arm against the torso,\n"
    "                          a hand against a thigh, the thighs) where their skins meet in a crease, so that\n"
    "                          posing them apart leaves no tissue web (default on)\n";

const char* kPoseUsage =
    "usage: repose pose --case CASE_DIR --pose FILE --out DIR [--skinning dqs|lbs] [--image FILE] [--format EXT]\n"
    "                   [--mesh FILE ...] [--relax [--relax-model M] [--poisson NU]] [--compare lbs,dqs,dqs+fem]\n"
    "                   [--displacement-field NAME]\n"
    "  Writes DIR/posed_labels<ext> with its names and colours beside it (posed_labels.tsv, and\n"
    "  posed_labels.ctbl for 3D Slicer), DIR/posed_mesh.vtu, DIR/posed_surfaces.vtp and, with --image,\n"
    "  DIR/posed_image<ext of the image>. --format (.nii.gz, .nii, .nrrd, .mha, .mhd) sets the label\n"
    "  volume's format; default: the format of the case's labels. --format vti writes both volumes as VTK XML\n"
    "  image data with their direction matrix: ParaView opens them lined up with posed_mesh.vtu\n"
    "  --format vdb            OpenVDB instead (Houdini, Blender): DIR/posed_labels.vdb holds an Int32 grid 'labels'\n"
    "                          (background 0) and a float fog grid 'label_<value>' per label; with --image,\n"
    "                          DIR/posed_image.vdb holds a float grid 'ct'. Each grid's transform is the volume's\n"
    "                          origin, spacing and direction (LPS millimetres)\n"
    "  --displacement-field NAME  also write DIR/NAME (a file name ending .nii.gz, .nii, .nrrd, .mha or .mhd; or\n"
    "                          just that extension: DIR/posed_displacement<ext>): for every voxel of the posed grid,\n"
    "                          the displacement in mm along the LPS axes from its centre to the rest point the posed\n"
    "                          CT is sampled at (ITK's displacement-field convention, a 3-float vector image; 0\n"
    "                          outside the body). Warping the rest CT by it (itk::WarpImageFilter, linear) gives\n"
    "                          posed_image: a known-answer case for deformable registration\n"
    "  --mesh FILE             also pose this mesh (.obj, .stl, .ply, .vtp, .vtk; repeat for several): organs,\n"
    "                          vessels, a catheter path (polylines and points too). Written as DIR/posed_<file name>\n"
    "                          in its own format, point and cell data kept where the format holds them. Each vertex\n"
    "                          is bound once to the rest tet mesh (vertices outside the body: the nearest tet,\n"
    "                          extrapolated) and the binding is cached in CASE_DIR/bindings/, the only place pose\n"
    "                          writes into a case (a read-only case is bound again on every run)\n"
    "  --relax                 refine the skinned pose by a static corotational FEM solve (bones stay rigid,\n"
    "                          soft tissue keeps its volume); --poisson NU (0.49); --relax-model fixed-corotated\n"
    "                          (default: nonlinear, Newton with a line search that never adds inverted tets) or\n"
    "                          linear (faster, volume kept to first order; --relax-iterations N outer iterations);\n"
    "                          --relax-volume segments (default: each body segment also keeps its volume as a whole,\n"
    "                          to 1e-5, against the volumetric locking of linear tets), tissues (each label within\n"
    "                          each segment: organs keep their own volume; slower), body or none (the paper's);\n"
    "                          --relax-continuation if-inverted (default: when tets stay inverted, a fold Newton\n"
    "                          cannot leave, the pose is solved again from the rest shape along rigid bone paths,\n"
    "                          with no tet inverted on the way; slower; not where a node is pinched between bones,\n"
    "                          which no path gets past), never or always;\n"
    "                          --relax-strained-region first (default: from a skinned start, the tets skinning\n"
    "                          strained, at the joints, and three rings around them are relaxed on their own before\n"
    "                          the whole mesh, when they hold at most 90 % of the free nodes) or off\n"
    "  --compare M,M,...       fidelity.csv and fidelity.png: body and per-label volume ratios, inverted tets and\n"
    "                          |det F - 1| for each of lbs, dqs, lbs+fem, dqs+fem\n";

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
    "                    label volume and CT of each frame are parts of animation.pvd too (ParaView)\n"
    "  --image FILE      also pose this CT/MRI (on the case's label grid) per frame (DIR/frames/image_NNNNN.*)\n"
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

/// The quality of the pipeline's current pose (its posed mesh against the rest mesh), labels named
/// from the case's table.
repose::PoseQuality poseQualityOf(repose::Pipeline& pipeline, const repose::DeformationStats& stats) {
  repose::LabelTable table;
  try {
    if (!pipeline.labelTableTsv().empty()) table = repose::parseLabelTable(pipeline.labelTableTsv());
  } catch (const std::invalid_argument&) {
    // A table that does not parse only costs the names (loadCase checked it).
  }
  return repose::poseQuality(stats, table, {}, pipeline.posedLabelStats());
}

void printTimings(const repose::Pipeline& pipeline, std::size_t from = 0) {
  const auto& t = pipeline.timings();
  for (std::size_t i = from; i < t.size(); ++i)
    std::cout << "  " << std::left << std::setw(16) << t[i].stage << std::right << std::fixed
              << std::setprecision(3) << std::setw(9) << t[i].seconds << " s\n";
  std::cout.unsetf(std::ios::floatfield);
}

std::vector<int> boneLabels(const std::string& skeletonJson) {
  std::vector<int> labels;
  for (const auto& j : repose::parseSkeletonJson(skeletonJson).joints)
    labels.insert(labels.end(), j.labels.begin(), j.labels.end());
  return labels;
}

std::string normalizedFormat(std::string ext) {
  if (!ext.empty() && ext[0] != '.') ext = "." + ext;
  for (const char* known : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd", ".vti"})
    if (ext == known) return ext;
  throw UsageError("unknown image format '" + ext + "' (use .nii.gz, .nii, .nrrd, .nhdr, .mha, .mhd or .vti)");
}

/// The file name of --displacement-field: a name in the output folder, or just its extension.
std::string displacementFileName(const std::string& value) {
  if (value.find('/') != std::string::npos)
    throw UsageError("--displacement-field takes a file name in the output folder, not a path ('" + value + "')");
  if (!value.empty() && value[0] == '.') return "posed_displacement" + normalizedFormat(value);
  for (const char* known : {".nii.gz", ".nii", ".nrrd", ".mha", ".mhd"}) {
    const std::string ext = known;
    if (value.size() > ext.size() && value.compare(value.size() - ext.size(), ext.size(), ext) == 0) return value;
  }
  throw UsageError("--displacement-field " + value + ": the name must end .nii.gz, .nii, .nrrd, .mha or .mhd");
}

/// The demo's pose: a hip flexed 60 deg, a knee 45 deg, a shoulder abducted 80 deg, an elbow 90 deg.
/// LPS frame: +x patient left, +y posterior, +z superior.
const char* kDemoPose = R"({
  "rotations": {
    "left_hip":       {"axis": [1, 0, 0], "degrees": -60},
    "left_knee":      {"axis": [1, 0, 0], "degrees": 45},
    "right_shoulder": {"axis": [0, 1, 0], "degrees": 80},
    "right_elbow":    {"axis": [1, 0, 0], "degrees": -90}
  },
  "translation": [0, 0, 0]
}
)";

vtkSmartPointer<vtkReposePhantomSource> makePhantom(const std::string& size, const std::string& rest = "apart") {
  auto phantom = vtkSmartPointer<vtkReposePhantomSource>::New();
  if (size != "tiny" && size != "small" && size != "medium" && size != "large")
    throw UsageError("unknown --size '" + size + "' (use tiny, small, medium or large)");
  if (rest != "apart" && rest != "contact")
    throw UsageError("unknown --rest-pose '" + rest + "' (use apart or contact)");
  phantom->SetSizeName(size.c_str());
  phantom->SetRestPoseName(rest.c_str());
  phantom->Update();
  if (!phantom->GetOutput() || !phantom->GetOutput()->GetPointData())
    throw std::runtime_error("phantom: cannot build the phantom");
  return phantom;
}

int runPhantom(const Options& o) {
  if (o.help) return std::cout << kPhantomUsage, 0;
  const std::string outDir = o.require("out");
  auto phantom = makePhantom(o.get("size", "small"), o.get("rest-pose", "apart"));
  repose::AtomicOutputs out(outDir);
  repose::writeLabelImage(phantom->GetOutput(), out.stage("labels.nii.gz"));
  repose::writeTextFile(out.stage("skeleton.json"), phantom->GetSkeletonJSON());
  repose::writeTextFile(out.stage("labels.tsv"), phantom->GetLabelTableTSV());
  out.commit();
  int d[3];
  phantom->GetOutput()->GetDimensions(d);
  std::cout << "phantom: " << d[0] << "x" << d[1] << "x" << d[2] << " voxels written to " << outDir << "\n";
  return 0;
}

void prepareCase(repose::Pipeline& pipeline, vtkImageData* labels, const std::string& labelsName,
                 const std::string& skeletonJson, const std::string& skeletonName, vtkImageData* image,
                 const std::string& imageName, const Options& o, const std::string& caseDir,
                 const std::string& labelsExt) {
  repose::PrepareSettings s;
  s.bodyThreshold = o.number("body-threshold", s.bodyThreshold);
  s.meshSpacing = o.number("mesh-spacing", s.meshSpacing);
  s.maxTets = o.number("max-tets", s.maxTets);
  if (s.maxTets != 0 && s.maxTets < 1000) throw UsageError("--max-tets must be 0 (no budget) or at least 1000");
  s.radiusEdgeRatio = o.number("quality", s.radiusEdgeRatio);
  s.maxInfluences = static_cast<int>(o.number("influences", s.maxInfluences));
  s.surfaceReduction = o.number("surface-reduction", s.surfaceReduction);
  if (s.maxInfluences < 1 || s.maxInfluences > 16) throw UsageError("--influences must be between 1 and 16");
  if (s.meshSpacing < 0) throw UsageError("--mesh-spacing must not be negative");
  if (s.radiusEdgeRatio < 1.1) throw UsageError("--quality must be at least 1.1 (TetGen does not terminate below)");
  if (s.surfaceReduction < 0 || s.surfaceReduction >= 1) throw UsageError("--surface-reduction must be in [0, 1)");
  const std::string separation = o.get("contact-separation", "on");
  if (separation != "on" && separation != "off")
    throw UsageError("--contact-separation takes on or off, not '" + separation + "'");
  s.separateContacts = separation == "on";
  pipeline.prepare(labels, labelsName, skeletonJson, skeletonName, image, imageName, s);
  pipeline.saveCase(caseDir, labelsExt);
  for (const auto& line : pipeline.reportLines()) std::cout << "  " << line << "\n";
}

/// The label table a volume is read with: --label-table, else the table beside the volume (see
/// repose::findLabelTableBeside), else the built-in TotalSegmentator names.
struct LabelTableChoice {
  repose::LabelTable table;
  std::string text;    // the file's text; empty for the built-in names
  std::string path;    // the file; empty for the built-in names
  std::string origin;  // for the console
};

LabelTableChoice builtinLabelTable(const std::string& labelsPath) {
  LabelTableChoice c;
  c.table = repose::builtinTotalSegmentatorTable();
  c.origin = "built-in TotalSegmentator names (no --label-table given, none found beside " + labelsPath + ")";
  return c;
}

/// Reads a label table; a file that holds none is an error naming it.
repose::LabelTable readLabelTable(const std::string& path, const std::string& text) {
  repose::LabelTable table;
  try {
    table = repose::parseLabelTable(text, path);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  if (table.labels.empty())
    throw std::runtime_error(path + ": holds no labels (expected value<TAB>name[<TAB>kind] or value name R G B A lines)");
  return table;
}

LabelTableChoice chooseLabelTable(const std::string& labelsPath, const Options& o) {
  LabelTableChoice c;
  if (o.has("label-table")) {
    c.path = o.get("label-table");
    c.text = repose::readTextFile(c.path);
    c.table = readLabelTable(c.path, c.text);
    c.origin = c.path;
    return c;
  }
  for (const std::string& path : repose::labelTablesBeside(labelsPath)) {
    c.path = path;
    c.text = repose::readTextFile(path);
    try {
      c.table = readLabelTable(path, c.text);
    } catch (const std::runtime_error& e) {
      // NAME.txt beside the volume may be notes rather than a Slicer colour table: not an error.
      if (repose::imageExtension(path) != ".txt") throw;
      std::cout << "label table: ignoring " << path << " (" << e.what() << ")" << std::endl;
      continue;
    }
    c.origin = path + " (found beside " + labelsPath + ")";
    return c;
  }
  return builtinLabelTable(labelsPath);
}

/// A table whose bone names contradict where the bones lie is the wrong table: say so, naming it.
void requireTableFits(vtkImageData* labels, const std::string& labelsPath, const LabelTableChoice& c) {
  repose::LabelVolume volume;
  if (!repose_vtk::ToVolume(labels, volume)) throw std::runtime_error(labelsPath + ": not a label volume");
  const repose::LabelTableFit fit = repose::checkLabelTableFit(volume, c.table);
  if (fit.fits()) return;
  if (c.path.empty())
    throw std::runtime_error(labelsPath + ": the built-in TotalSegmentator names do not fit it (no --label-table given, "
                             "none found beside it): " + fit.problem() + "; give its label table with --label-table");
  throw std::runtime_error(c.path + ": does not fit " + labelsPath + ": " + fit.problem() +
                           "; give the volume's own label table with --label-table");
}

struct RigResult {
  vtkSmartPointer<vtkImageData> labels;  // relabelled when a label held several bones or fragments moved
  std::string skeletonJson, report, tableTsv;
  bool relabelled = false;
};

RigResult rigLabels(vtkImageData* labels, const std::string& labelsName, const Options& o) {
  const LabelTableChoice table = chooseLabelTable(labelsName, o);
  requireTableFits(labels, labelsName, table);
  auto rig = vtkSmartPointer<vtkReposeAutoRig>::New();
  rig->SetInputData(labels);
  rig->SetLabelTableTSV(table.text.c_str());
  rig->SetLabelTableName(table.origin.c_str());  // the report's "label table:" line
  rig->CheckLabelTableOff();  // checked above, with the file names
  if (o.has("max-gap")) rig->SetMaxGapMm(o.number("max-gap", 6));
  const std::string what = "automatic skeleton of " + labelsName;
  repose::updateOrThrow(rig, what);
  RigResult r;
  r.labels = vtkSmartPointer<vtkImageData>::New();
  r.labels->ShallowCopy(rig->GetOutput());
  r.skeletonJson = rig->GetSkeletonJSON();
  r.report = rig->GetReport();
  r.tableTsv = rig->GetOutputLabelTableTSV();
  if (rig->GetNumberOfJoints() < 2)
    throw std::runtime_error(labelsName + ": the automatic skeleton found " + std::to_string(rig->GetNumberOfJoints()) +
                             " joint(s) with the label table " + (table.path.empty() ? "of TotalSegmentator" : table.path) +
                             "; name the bones with --label-table or write skeleton.json by hand");
  vtkDataArray* a = labels->GetPointData()->GetScalars();
  vtkDataArray* b = r.labels->GetPointData()->GetScalars();
  for (vtkIdType i = 0, n = a->GetNumberOfTuples(); i < n && !r.relabelled; ++i)
    r.relabelled = a->GetTuple1(i) != b->GetTuple1(i);
  return r;
}

int runRig(const Options& o) {
  if (o.help) return std::cout << kRigUsage, 0;
  const std::string labelsPath = o.require("labels");
  const std::string outPath = o.require("out");
  const std::filesystem::path out(outPath);
  const std::string dir = out.has_parent_path() ? out.parent_path().string() : ".";
  repose::refuseOutputsOverInputs(dir, {out.filename().string(), "labels_rigged.nii.gz", "labels_rigged.tsv"},
                                  {{labelsPath, o.get("label-table")}, {}});
  auto labels = repose::readLabelVolume(labelsPath);
  const RigResult r = rigLabels(labels, labelsPath, o);
  repose::AtomicOutputs files(dir);
  repose::writeTextFile(files.stage(out.filename().string()), r.skeletonJson);
  if (r.relabelled) {
    repose::writeLabelImage(r.labels, files.stage("labels_rigged.nii.gz"));
    repose::writeTextFile(files.stage("labels_rigged.tsv"), r.tableTsv);
  }
  files.commit();
  std::cout << r.report;
  std::cout << "skeleton written to " << outPath
            << (r.relabelled ? " (it refers to the relabelled " + dir + "/labels_rigged.nii.gz, table labels_rigged.tsv)"
                             : std::string())
            << "\n";
  return 0;
}

/// The label table kept in a case prepared from a hand-written skeleton: the chosen table; the
/// built-in TotalSegmentator names (of the values present) only when they fit the volume; else ""
/// (the case then names its labels label_<value>, see Pipeline::saveCase).
std::string caseLabelTable(vtkImageData* labels, const std::string& labelsPath, const Options& o) {
  const LabelTableChoice c = chooseLabelTable(labelsPath, o);
  if (!c.path.empty()) {
    std::cout << "label table: " << c.origin << std::endl;
    return repose::labelTableToTsv(c.table);
  }
  repose::LabelVolume volume;
  if (!repose_vtk::ToVolume(labels, volume)) return "";
  const std::set<int> present(volume.data.begin(), volume.data.end());
  const repose::LabelTableFit fit = repose::checkLabelTableFit(volume, c.table);
  const bool named = fit.checked >= 3 && fit.fits() &&
                     std::all_of(present.begin(), present.end(), [&](int v) { return v == 0 || c.table.find(v); });
  if (!named) {
    std::cout << "label table: none given or found beside " << labelsPath << "; the case names its labels label_<value>"
              << std::endl;
    return "";
  }
  repose::LabelTable table;
  for (const repose::LabelInfo& l : c.table.labels)
    if (present.count(l.value)) table.labels.push_back(l);
  std::cout << "label table: " << c.origin << std::endl;
  return repose::labelTableToTsv(table);
}

int runPrepare(const Options& o) {
  if (o.help) return std::cout << kPrepareUsage, 0;
  const std::string labelsPath = o.require("labels");
  const std::string skeletonPath = o.require("skeleton");
  const std::string caseDir = o.require("out");
  std::string ext = repose::imageExtension(labelsPath);
  if (ext != ".nii.gz" && ext != ".nii" && ext != ".nrrd" && ext != ".mha") ext = ".nii.gz";
  repose::refuseOutputsOverInputs(caseDir, repose::Pipeline::caseFileNames(ext),
                                  {{labelsPath, skeletonPath, o.get("image"), o.get("label-table")}, {}});
  repose::Pipeline pipeline;
  pipeline.setProgress([](const std::string& s) { std::cout << "prepare: " << s << "..." << std::endl; });
  vtkSmartPointer<vtkImageData> labels = repose::readLabelVolume(labelsPath);
  std::string skeletonJson, tableTsv;
  if (skeletonPath == "auto") {
    std::cout << "prepare: finding the skeleton from the bone labels..." << std::endl;
    const RigResult r = rigLabels(labels, labelsPath, o);
    std::cout << r.report;
    labels = r.labels;
    skeletonJson = r.skeletonJson;
    tableTsv = r.tableTsv;
  } else {
    skeletonJson = repose::readTextFile(skeletonPath);
    tableTsv = caseLabelTable(labels, labelsPath, o);
  }
  vtkSmartPointer<vtkImageData> image;
  if (o.has("image")) image = repose::readIntensityImage(o.get("image"));
  pipeline.setLabelTableTsv(tableTsv);
  prepareCase(pipeline, labels, labelsPath, skeletonJson, skeletonPath == "auto" ? "automatic skeleton" : skeletonPath,
              image, o.get("image"), o, caseDir, ext);
  std::cout << "prepared case written to " << caseDir << " (label table: " << caseDir << "/labels.tsv)\n";
  printTimings(pipeline);
  return 0;
}

/// Poses a loaded pipeline and writes the posed outputs into `out`.
/// The case's label table beside a label output: BASE.tsv (Repose's, with kinds) and BASE.ctbl
/// (3D Slicer's colour table), so names and colours travel with the volume.
void writeLabelTables(repose::Pipeline& pipeline, repose::AtomicOutputs& out, const std::string& base) {
  if (pipeline.labelTableTsv().empty()) return;
  const repose::LabelTable table = repose::parseLabelTable(pipeline.labelTableTsv(), "the case's label table");
  repose::writeTextFile(out.stage(base + ".tsv"), repose::labelTableToTsv(table));
  repose::writeTextFile(out.stage(base + ".ctbl"), repose::labelTableToSlicerColorTable(table));
}

void writePosed(repose::Pipeline& pipeline, repose::AtomicOutputs& out, const std::string& labelsExt,
                const std::string& imageExt) {
  repose::writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
  repose::writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
  repose::writeLabelImage(pipeline.posedLabels(), out.stage("posed_labels" + labelsExt));
  writeLabelTables(pipeline, out, "posed_labels");
  if (vtkImageData* image = pipeline.posedImage()) repose::writeImage(image, out.stage("posed_image" + imageExt));
}

/// The methods of --compare: "lbs", "dqs", "lbs+fem", "dqs+fem".
std::vector<std::string> parseCompare(const Options& o) {
  std::vector<std::string> methods;
  if (!o.has("compare")) return methods;
  std::stringstream in(o.get("compare"));
  for (std::string m; std::getline(in, m, ',');) {
    if (m != "lbs" && m != "dqs" && m != "lbs+fem" && m != "dqs+fem")
      throw UsageError("--compare takes lbs, dqs, lbs+fem, dqs+fem (comma separated), not '" + m + "'");
    methods.push_back(m);
  }
  if (methods.empty()) throw UsageError("--compare needs at least one method");
  return methods;
}

/// Fidelity of every compared method at the current pose: one CSV row each, and the volume ratios
/// for the plot. The pipeline's own method and relaxation are restored afterwards.
struct FidelityReport {
  std::vector<std::string> methods;
  std::ostringstream rows;
  std::vector<std::int32_t> labels;  // columns, fixed by the first row
  std::map<std::string, std::vector<std::pair<double, double>>> series;

  void addFrame(repose::Pipeline& pipeline, int frame, const std::string& userMethod, bool userRelax, double nu,
                int iterations) {
    for (const std::string& m : methods) {
      pipeline.setSkinningMethod(m.substr(0, 3));
      pipeline.setRelaxation(m.size() > 3, nu, iterations);
      const repose::DeformationStats s = pipeline.posedStats();
      if (labels.empty())
        for (const auto& [label, ratio] : s.labelVolumeRatio) labels.push_back(label);
      rows << frame << "," << m << "," << s.volumeRatio << "," << s.invertedTets << "," << s.meanAbsDetFMinus1 << ","
           << s.maxAbsDetFMinus1;
      for (auto label : labels) {
        auto it = s.labelVolumeRatio.find(label);
        rows << "," << (it == s.labelVolumeRatio.end() ? 0.0 : it->second);
      }
      rows << "\n";
      series[m].push_back({double(frame), s.volumeRatio});
    }
    pipeline.setSkinningMethod(userMethod);
    pipeline.setRelaxation(userRelax, nu, iterations);
  }
  void write(repose::AtomicOutputs& out) const {
    std::ostringstream csv;
    csv << "frame,method,body_volume_ratio,inverted_tets,mean_abs_detF_minus_1,max_abs_detF_minus_1";
    for (auto label : labels) csv << ",label_" << label << "_volume_ratio";
    csv << "\n" << rows.str();
    repose::writeTextFile(out.stage("fidelity.csv"), csv.str());
    repose::plotVolumeRatios(series, out.stage("fidelity.png"));
  }
};

/// Charts need an X display: without one, run again under xvfb-run when it is installed.
void requireDisplay(int argc, char** argv, const char* why);

void applyRelaxation(repose::Pipeline& pipeline, const Options& o) {
  // Regions and continuation also serve the +fem methods of --compare.
  pipeline.setRelaxationVolume(o.get("relax-volume", "segments"));
  const std::string continuation = o.get("relax-continuation", "if-inverted");
  if (continuation != "if-inverted" && continuation != "never" && continuation != "always")
    throw UsageError("--relax-continuation must be if-inverted, never or always");
  pipeline.setRelaxationContinuation(continuation);
  const std::string strainedRegion = o.get("relax-strained-region", "first");
  if (strainedRegion != "first" && strainedRegion != "off")
    throw UsageError("--relax-strained-region must be first or off");
  pipeline.setRelaxationStrainedRegion(strainedRegion);
  if (!o.has("relax")) {
    if (o.has("relax-iterations") || o.has("poisson") || o.has("relax-model") ||
        ((o.has("relax-volume") || o.has("relax-continuation") || o.has("relax-strained-region")) && !o.has("compare")))
      throw UsageError("--relax-model, --relax-iterations, --relax-volume, --relax-continuation, "
                       "--relax-strained-region and --poisson need --relax");
    return;
  }
  const std::string model = o.get("relax-model", "fixed-corotated");
  if (model != "fixed-corotated" && model != "linear")
    throw UsageError("--relax-model must be fixed-corotated or linear");
  pipeline.setRelaxationModel(model);
  const double nu = o.number("poisson", 0.49);
  const double iterations = o.number("relax-iterations", 1);
  if (!(nu > -1 && nu < 0.5)) throw UsageError("--poisson must be in (-1, 0.5)");
  if (iterations < 1 || iterations != std::floor(iterations)) throw UsageError("--relax-iterations must be a whole number >= 1");
  pipeline.setRelaxation(true, nu, static_cast<int>(iterations));
}

/// The --mesh files bound to the case's rest mesh (binding cache in CASE_DIR/bindings).
std::unique_ptr<repose::MeshPoser> bindMeshes(repose::Pipeline& pipeline, const Options& o, const std::string& caseDir) {
  const std::vector<std::string> paths = o.all("mesh");
  if (paths.empty()) return nullptr;
  std::set<std::string> names;
  for (const auto& path : paths) {
    if (!repose::isSurfaceMeshPath(path))
      throw std::runtime_error(path + ": unknown mesh format (expected .obj, .stl, .ply, .vtp or .vtk)");
    // Stems, not names: animate writes every mesh's frames as <stem>_NNNNN.vtp.
    if (!names.insert(std::filesystem::path(path).stem().string()).second)
      throw UsageError("two --mesh files are named " + std::filesystem::path(path).filename().string() +
                       " (their outputs would collide)");
  }
  auto poser = std::make_unique<repose::MeshPoser>(pipeline.restMesh());
  for (const auto& path : paths) {
    const repose::PoseableMesh& m = poser->add(path, caseDir + "/bindings");
    const vtkIdType n = m.rest->GetNumberOfPoints();
    std::cout << "mesh " << path << ": " << n << " vertices, " << m.outside << " outside the body ("
              << std::fixed << std::setprecision(1) << 100.0 * double(m.outside) / double(std::max<vtkIdType>(n, 1))
              << " %), " << (m.fromCache ? "binding read from the cache" : "bound") << " in " << std::setprecision(3)
              << m.bindSeconds << " s\n";
    std::cout.unsetf(std::ios::floatfield);
    if (!m.cacheWarning.empty()) std::cerr << "repose: warning: binding not cached: " << m.cacheWarning << "\n";
  }
  return poser;
}

void writePosedMeshes(repose::Pipeline& pipeline, const repose::MeshPoser& poser, repose::AtomicOutputs& out) {
  for (std::size_t i = 0; i < poser.meshes().size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    vtkSmartPointer<vtkPolyData> posed = poser.pose(i, pipeline.posedMesh());
    const double ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string name = repose::posedMeshName(poser.meshes()[i].path);
    repose::writeSurfaceMesh(posed, out.stage(name));
    std::cout << "mesh " << poser.meshes()[i].path << ": posed in " << std::fixed << std::setprecision(1) << ms
              << " ms -> " << name << "\n";
    std::cout.unsetf(std::ios::floatfield);
  }
}

/// --format vdb: the posed label volume (and image) as sparse OpenVDB grids.
void writePosedVdb(repose::Pipeline& pipeline, repose::AtomicOutputs& out, double imageBackground) {
  auto describe = [](const std::string& name, const repose::VdbWriteReport& r, std::size_t voxels, std::size_t bytes) {
    std::cout << "vdb " << name << ": " << r.grids << " grid(s), " << r.activeVoxels << " of " << voxels
              << " voxels active (" << std::fixed << std::setprecision(1) << 100.0 * double(r.activeVoxels) / double(voxels)
              << " %), " << double(r.memoryBytes) / 1e6 << " MB sparse vs " << double(bytes) / 1e6
              << " MB dense, built in " << std::setprecision(3) << r.buildSeconds << " s, written in " << r.writeSeconds
              << " s\n";
    std::cout.unsetf(std::ios::floatfield);
  };
  repose::LabelVolume labels;
  if (!repose_vtk::ToVolume(pipeline.posedLabels(), labels)) throw std::runtime_error("posed labels: not a volume");
  const repose::VdbWriteReport r = repose::writeLabelsVdb(labels, out.stage("posed_labels.vdb"));
  describe("posed_labels.vdb", r, labels.data.size(), labels.data.size() * sizeof(std::int32_t));
  if (vtkImageData* image = pipeline.posedImage()) {
    repose::IntensityVolume ct;
    if (!repose_vtk::ToVolume(image, ct)) throw std::runtime_error("posed image: not a volume");
    const repose::VdbWriteReport ri =
        repose::writeIntensityVdb(ct, static_cast<float>(imageBackground), out.stage("posed_image.vdb"), "ct");
    describe("posed_image.vdb", ri, ct.data.size(), ct.data.size() * sizeof(float));
  }
}

/// Every file `pose` may write (each format's posed volumes), so that none can replace an input.
std::vector<std::string> poseOutputNames(const std::vector<std::string>& meshes) {
  std::vector<std::string> names = {"posed_mesh.vtu", "posed_surfaces.vtp", "fidelity.csv", "fidelity.png"};
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".raw.gz", ".mha", ".mhd", ".raw", ".zraw", ".vdb"})
    for (const char* stem : {"posed_labels", "posed_image"}) names.push_back(stem + std::string(ext));
  for (const std::string& mesh : meshes) names.push_back(repose::posedMeshName(mesh));
  return names;
}

/// The files named by the options `names`, and every --mesh.
std::vector<std::string> inputFiles(const Options& o, const std::vector<std::string>& names) {
  std::vector<std::string> files = o.all("mesh");
  for (const std::string& n : names) files.push_back(o.get(n));
  return files;
}

bool isVdbFormat(const std::string& format) { return format == "vdb" || format == ".vdb"; }

int runPose(const Options& o, int argc, char** argv) {
  if (o.help) return std::cout << kPoseUsage, 0;
  if (o.has("compare")) requireDisplay(argc, argv, "fidelity.png");
  const std::string caseDir = o.require("case");
  const std::string posePath = o.require("pose");
  const std::string outDir = o.require("out");
  repose::refuseOutputsOverInputs(outDir, poseOutputNames(o.all("mesh")), {inputFiles(o, {"pose", "image"}), {caseDir}});
  repose::Pipeline pipeline;
  pipeline.setProgress(repose::throttledConsoleProgress("pose: "));
  pipeline.loadCase(caseDir);
  pipeline.setPose(repose::readTextFile(posePath), posePath);
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  applyRelaxation(pipeline, o);
  std::string imageExt = ".nii.gz";
  double imageBackground = 0;
  if (o.has("image")) {
    const std::string imagePath = o.get("image");
    vtkSmartPointer<vtkImageData> image = repose::readIntensityImage(imagePath);
    pipeline.setRestImage(image, imagePath);
    imageExt = repose::imageExtension(imagePath);
    double range[2];
    image->GetPointData()->GetScalars()->GetRange(range);
    imageBackground = range[0];  // the posed image's air outside the body (see Pipeline::setRestImage)
  }
  const bool vdb = isVdbFormat(o.get("format"));
  const std::string labelsExt =
      vdb ? ".vdb" : o.has("format") ? normalizedFormat(o.get("format")) : pipeline.labelsExtension();
  if (labelsExt == ".vti") imageExt = ".vti";  // for ParaView, the CT too
  const std::vector<std::string> compare = parseCompare(o);
  const std::string displacementName = o.has("displacement-field") ? displacementFileName(o.get("displacement-field")) : "";
  std::unique_ptr<repose::MeshPoser> meshes = bindMeshes(pipeline, o, caseDir);
  repose::AtomicOutputs out(outDir);
  if (vdb) {
    repose::writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
    repose::writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
    writePosedVdb(pipeline, out, imageBackground);
    writeLabelTables(pipeline, out, "posed_labels");
  } else {
    writePosed(pipeline, out, labelsExt, imageExt);
  }
  if (meshes) writePosedMeshes(pipeline, *meshes, out);
  if (!displacementName.empty()) repose::writeImage(pipeline.posedDisplacement(), out.stage(displacementName));
  if (!compare.empty()) {
    FidelityReport fidelity;
    fidelity.methods = compare;
    fidelity.addFrame(pipeline, 0, o.get("skinning", "dqs"), o.has("relax"), o.number("poisson", 0.49),
                      int(o.number("relax-iterations", 1)));
    fidelity.write(out);
  }
  const repose::PoseQuality quality = poseQualityOf(pipeline, pipeline.posedStats());
  out.commit();
  if (o.has("relax")) std::cout << pipeline.relaxationSummary() << "\n";
  std::cout << "posed outputs written to " << outDir << "\n";
  std::cout << "quality: " << quality.summary << "\n";
  for (const std::string& w : quality.warnings) std::cerr << "warning: " << w << "\n";
  printTimings(pipeline);
  return 0;
}

struct FrameRange {
  int start = 0, stop = -1, step = 1;
};

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

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

/// The clip retargeted onto the skeleton; says the clip's units and which joints it drives, and warns
/// (or with --strict fails) when recognised limb joints are left undriven.
std::unique_ptr<repose::BvhRetargeter> retargetClip(const Options& o, const repose::Skeleton& skeleton,
                                                    const repose::BvhMotion& motion, const std::string& bvhPath) {
  repose::BvhJointMap map;
  repose::JointMapCoverage coverage;
  try {
    map = o.has("map") ? repose::readJointMapFile(o.get("map")) : repose::defaultCmuJointMap(motion, skeleton);
    coverage = repose::jointMapCoverage(skeleton, map);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error((o.has("map") ? o.get("map") + ": " : bvhPath + ": ") + e.what());
  }
  repose::RetargetOptions options;
  options.mode = repose::parseRetargetMode(o.get("mode", "direction"));
  options.referenceFrame = static_cast<int>(o.number("reference-frame", 0));
  options.translateRoot = !o.has("no-root-motion");
  options.unitScaleMm = o.number("unit-mm", 0);
  std::unique_ptr<repose::BvhRetargeter> retargeter;
  try {
    retargeter = std::make_unique<repose::BvhRetargeter>(motion, skeleton, map, options);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(bvhPath + ": " + e.what());
  }
  const repose::BvhUnits& units = retargeter->units();
  char line[256];
  if (o.has("unit-mm"))
    std::snprintf(line, sizeof(line), "%g mm per unit (--unit-mm)", units.mmPerUnit);
  else
    std::snprintf(line, sizeof(line), "%s (%s %.1f units), %.*f mm per unit; --unit-mm overrides", units.name.c_str(),
                  units.measure.c_str(), units.measuredUnits, units.mmPerUnit < 100 ? 2 : 0, units.mmPerUnit);
  std::cout << "animate: BVH units: " << line << "\n";
  std::string driven;
  for (const auto& [joint, source] : coverage.driven) driven += (driven.empty() ? "" : ", ") + joint + " <- " + source;
  std::cout << "animate: the clip drives " << coverage.driven.size() << " of " << skeleton.size()
            << " joints: " << driven << "\n";
  if (!coverage.following.empty())
    std::cout << "animate: not driven, following their parents: " << joinNames(coverage.following) << "\n";
  std::vector<std::string> problems;
  if (!coverage.undrivenLimbs.empty())
    problems.push_back("the clip drives none of the limb joints " + joinNames(coverage.undrivenLimbs));
  if (!coverage.unknownNames.empty() && !o.has("map"))
    problems.push_back("the built-in map does not know the joint names " + joinNames(coverage.unknownNames) +
                       " (standard names: see --help)");
  for (const std::string& problem : problems) {
    if (o.has("strict"))
      throw std::runtime_error(bvhPath + ": " + problem + " (--strict): map them with --map FILE, JSON " +
                               "{\"BVH joint\": \"skeleton joint\"}");
    std::cout << "animate: warning: " << problem << ": they only follow their parents; map them with --map FILE "
              << "(JSON {\"BVH joint\": \"skeleton joint\"}), or --strict to stop here\n";
  }
  return retargeter;
}

int runAnimate(const Options& o, int argc, char** argv) {
  if (o.help) return std::cout << kAnimateUsage, 0;
  if (o.has("compare")) requireDisplay(argc, argv, "fidelity.png");
  const std::string caseDir = o.require("case");
  const std::string bvhPath = o.require("bvh");
  const std::string outDir = o.require("out");
  repose::refuseOutputsOverInputs(outDir, {"frames", "animation.pvd", "frames.csv", "fidelity.csv", "fidelity.png"},
                                  {inputFiles(o, {"bvh", "map", "image"}), {caseDir}});
  const std::string relaxStart = o.get("relax-start", "previous");
  if (relaxStart != "previous" && relaxStart != "skinned") throw UsageError("--relax-start must be previous or skinned");
  if (o.has("relax-start") && !o.has("relax") && !o.has("compare"))
    throw UsageError("--relax-start needs --relax (or --compare with a +fem method)");
  const double maxVoxels = parseVoxelCount(o.get("max-voxels", "512M"));
  if (o.has("unit-mm") && !(o.number("unit-mm", 0) > 0)) throw UsageError("--unit-mm needs a positive number of millimetres");
  repose::Pipeline pipeline;
  pipeline.setProgress(repose::throttledConsoleProgress("animate: "));
  pipeline.loadCase(caseDir);
  pipeline.setMaxPosedVoxels(maxVoxels);
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  pipeline.setRelaxationWarmStart(relaxStart == "previous");
  applyRelaxation(pipeline, o);
  const repose::Skeleton skeleton = repose::parseSkeletonJson(pipeline.skeletonJson());

  repose::BvhMotion motion;
  try {
    motion = repose::readBvhFile(bvhPath);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  const std::unique_ptr<repose::BvhRetargeter> retargeter = retargetClip(o, skeleton, motion, bvhPath);
  const FrameRange range = parseFrames(o.get("frames"), motion.frameCount);
  const std::size_t frameCount = std::size_t(std::max(0, (range.stop - range.start + range.step - 1) / range.step));
  const auto animateStart = std::chrono::steady_clock::now();
  const bool volumes = o.has("volumes");
  FidelityReport fidelity;
  fidelity.methods = parseCompare(o);
  std::string imageExt;
  if (o.has("image")) {
    pipeline.setRestImage(repose::readIntensityImage(o.get("image")), o.get("image"));
    imageExt = repose::imageExtension(o.get("image"));
  }
  if (o.has("format") && !o.has("volumes") && !o.has("image"))
    throw UsageError("--format sets the format of the frames' volumes: it needs --volumes or --image");
  const std::string volumeExt = o.has("format") ? normalizedFormat(o.get("format")) : ".nii.gz";
  if (o.has("format")) imageExt = volumeExt;
  const bool volumesInPvd = volumeExt == ".vti";

  std::unique_ptr<repose::MeshPoser> meshes = bindMeshes(pipeline, o, caseDir);
  const int volumePart = 2 + int(meshes ? meshes->meshes().size() : 0);  // after the mesh, surfaces and meshes
  repose::AtomicOutputs out(outDir);
  repose::makeDirectories(out.stage("frames"));
  if (volumes) writeLabelTables(pipeline, out, "frames/labels");
  const double restVolume = pipeline.restMeshVolume();
  std::map<int, long> restCounts;
  if (volumes) restCounts = labelCounts(pipeline.restLabels());
  std::vector<repose::PvdEntry> entries;
  std::ostringstream csv;
  csv << "frame,time_s,body_volume_ratio,posing_ms";
  for (const auto& [label, count] : restCounts) csv << ",label_" << label << "_ratio";
  const bool relaxing = o.has("relax");
  if (relaxing)
    csv << ",relax_s,newton_iterations,cg_iterations,inverted_tets,continuation_steps,warm_start,"
           "strained_region_nodes,strained_region_newton_iterations,pinched_nodes";
  csv << ",mesh_inverted_tets,max_stretch,stretched_ml" << (volumes ? ",contested_bone_voxels" : "") << "\n";
  std::vector<std::pair<int, repose::PoseQuality>> warned;  // frames with warnings
  int written = 0;
  double totalPosing = 0, worstPosing = 0, largestVolume = 0;
  int largestDims[3] = {0, 0, 0};
  for (int f = range.start; f < range.stop; f += range.step) {
    char name[64];
    pipeline.setPose(retargeter->pose(f));
    if (!fidelity.methods.empty())
      fidelity.addFrame(pipeline, f, o.get("skinning", "dqs"), o.has("relax"), o.number("poisson", 0.49),
                        int(o.number("relax-iterations", 1)));
    // Posing time of the frame as the user asked for it (the comparison's methods are not counted).
    const auto t0 = std::chrono::steady_clock::now();
    vtkUnstructuredGrid* mesh = pipeline.posedMesh();
    vtkPolyData* surfaces = pipeline.posedSurfaces();
    vtkImageData* labels = nullptr;
    vtkImageData* image = nullptr;
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
    for (vtkImageData* volume : {labels, image})
      if (volume && double(volume->GetNumberOfPoints()) > largestVolume) {
        largestVolume = double(volume->GetNumberOfPoints());
        volume->GetDimensions(largestDims);
      }
    const double posing = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    totalPosing += posing;
    worstPosing = std::max(worstPosing, posing);
    const double time = f * motion.frameTime;
    std::snprintf(name, sizeof(name), "frames/mesh_%05d.vtu", f);
    repose::writeMesh(mesh, out.stage(name));
    entries.push_back({time, 0, name});
    std::snprintf(name, sizeof(name), "frames/surfaces_%05d.vtp", f);
    repose::writeSurfaces(surfaces, out.stage(name));
    entries.push_back({time, 1, name});
    for (std::size_t i = 0; meshes && i < meshes->meshes().size(); ++i) {
      std::snprintf(name, sizeof(name), "_%05d.vtp", f);
      const std::string file = "frames/" + std::filesystem::path(meshes->meshes()[i].path).stem().string() + name;
      repose::writeSurfaces(meshes->pose(i, mesh), out.stage(file));
      entries.push_back({time, int(2 + i), file});
    }
    csv << f << "," << time << "," << pipeline.posedMeshVolume() / restVolume << "," << posing * 1e3;
    if (labels) {
      std::snprintf(name, sizeof(name), "frames/labels_%05d", f);
      repose::writeLabelImage(labels, out.stage(name + volumeExt));
      if (volumesInPvd) entries.push_back({time, volumePart, name + volumeExt});
      const auto counts = labelCounts(labels);
      for (const auto& [label, count] : restCounts) {
        auto it = counts.find(label);
        csv << "," << double(it == counts.end() ? 0 : it->second) / double(count);
      }
    }
    if (image) {
      std::snprintf(name, sizeof(name), "frames/image_%05d", f);
      repose::writeImage(image, out.stage(name + imageExt));
      if (volumesInPvd) entries.push_back({time, volumePart + 1, name + imageExt});
    }
    if (vtkReposeCorotationalRelax* relax = relaxing ? pipeline.relaxation() : nullptr)
      csv << "," << relax->GetLastRelaxTime() << ","
          << relax->GetNewtonIterations() << ","
          << relax->GetCGIterations() << ","
          << relax->GetInvertedAfter() << ","
          << relax->GetContinuationSteps() << "," << int(relax->GetWarmStarted()) << ","
          << relax->GetStrainedRegionNodes() << "," << relax->GetStrainedRegionNewtonIterations() << ","
          << relax->GetPinchedNodes();
    const repose::DeformationStats stats = pipeline.posedStats();
    csv << "," << stats.invertedTets << "," << stats.maxStretch << "," << stats.stretchedVolumeMm3 / 1000.0;
    if (volumes) csv << "," << pipeline.posedLabelStats().contestedBoneVoxels;
    csv << "\n";
    repose::PoseQuality quality = poseQualityOf(pipeline, stats);
    if (!quality.warnings.empty()) warned.emplace_back(f, std::move(quality));
    ++written;
    if (written % 10 == 0)
      std::cout << "animate: " << repose::progressLine(std::size_t(written), frameCount, std::chrono::duration<double>(std::chrono::steady_clock::now() - animateStart).count(), "frames")
                << std::endl;
  }
  repose::writeTextFile(out.stage("animation.pvd"), repose::pvdText(entries));
  repose::writeTextFile(out.stage("frames.csv"), csv.str());
  if (!fidelity.methods.empty()) fidelity.write(out);
  out.commit();
  std::cout << "animate: " << written << " frames of " << bvhPath << " written to " << outDir << " (posing "
            << std::fixed << std::setprecision(1) << 1e3 * totalPosing / std::max(written, 1) << " ms mean, "
            << 1e3 * worstPosing << " ms worst per frame" << (volumes ? ", with the label volume" : "") << ")\n";
  if (largestVolume > 0)
    std::cout << "animate: largest posed volume " << largestDims[0] << " x " << largestDims[1] << " x " << largestDims[2]
              << " = " << std::setprecision(3) << largestVolume / 1e6 << " M voxels\n";
  // The frames that went wrong, the first few in full (every frame's figures are in frames.csv).
  std::cout << "animate: quality flagged " << warned.size() << " of " << written << " frames (frames.csv: "
            << "mesh_inverted_tets, max_stretch, stretched_ml" << (volumes ? ", contested_bone_voxels" : "") << ")\n";
  const std::size_t shown = std::min<std::size_t>(warned.size(), 3);
  for (std::size_t i = 0; i < shown; ++i)
    for (const std::string& w : warned[i].second.warnings)
      std::cerr << "warning: frame " << warned[i].first << ": " << w << "\n";
  if (warned.size() > shown) std::cerr << "warning: ... and " << warned.size() - shown << " more frames\n";
  return 0;
}

/// Rendering needs an X display; without one, run again under xvfb-run when it is installed.
bool reexecUnderXvfb(int argc, char** argv) {
  if (std::getenv("DISPLAY") || std::getenv("REPOSE_UNDER_XVFB")) return false;
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) return false;
  setenv("REPOSE_UNDER_XVFB", "1", 1);
  std::vector<char*> args;
  args.push_back(const_cast<char*>("xvfb-run"));
  args.push_back(const_cast<char*>("-a"));
  for (int i = 0; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  std::cout.flush();
  execvp("xvfb-run", args.data());
  return false;
}

void requireDisplay(int argc, char** argv, const char* why) {
  if (std::getenv("DISPLAY") || std::getenv("REPOSE_UNDER_XVFB")) return;
  reexecUnderXvfb(argc, argv);
  throw std::runtime_error(std::string(why) + " needs an X display: install xvfb (xvfb-run)");
}

int runDemo(const Options& o, int argc, char** argv) {
  if (o.help) return std::cout << kDemoUsage, 0;
  const bool render = !o.has("no-render");
  if (render) requireDisplay(argc, argv, "render.png (or pass --no-render)");
  const std::string outDir = o.get("out", "repose-demo");
  const std::string size = o.get("size", "small");
  repose::Pipeline pipeline;
  pipeline.setProgress([](const std::string& s) { std::cout << "demo: " << s << "..." << std::endl; });

  std::cout << "demo: building the " << size << " phantom..." << std::endl;
  auto phantom = makePhantom(size);
  vtkImageData* labels = phantom->GetOutput();
  const std::string skeletonJson = phantom->GetSkeletonJSON();

  repose::AtomicOutputs out(outDir);
  repose::writeLabelImage(labels, out.stage("rest_labels.nii.gz"));
  repose::writeTextFile(out.stage("skeleton.json"), skeletonJson);
  repose::writeTextFile(out.stage("pose.json"), kDemoPose);
  repose::writeTextFile(out.stage("labels.tsv"), phantom->GetLabelTableTSV());
  pipeline.setLabelTableTsv(phantom->GetLabelTableTSV());
  prepareCase(pipeline, labels, "phantom", skeletonJson, "phantom skeleton", nullptr, "", o, out.stage("case"),
              ".nii.gz");

  pipeline.setPose(kDemoPose, "demo pose");
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  std::cout << "demo: posing..." << std::endl;
  writePosed(pipeline, out, ".nii.gz", ".nii.gz");
  repose::writeSurfaces(pipeline.restSurfaces(), out.stage("rest_surfaces.vtp"));
  if (render) {
    std::cout << "demo: rendering..." << std::endl;
    repose::renderSideBySide(pipeline.restSurfaces(), pipeline.posedSurfaces(), boneLabels(skeletonJson),
                             out.stage("render.png"));
  }
  out.commit();
  int d[3];
  labels->GetDimensions(d);
  std::cout << "demo: " << d[0] << "x" << d[1] << "x" << d[2] << " voxels, "
            << pipeline.restMesh()->GetNumberOfPoints() << " nodes, " << pipeline.restMesh()->GetNumberOfCells()
            << " tets; outputs in " << outDir << "\nstage times:\n";
  printTimings(pipeline);
  return 0;
}

/// VTK's warnings and errors go to stderr as single lines; failures are reported by the caller.
class QuietOutputWindow : public vtkOutputWindow {
public:
  static QuietOutputWindow* New() { return new QuietOutputWindow; }
  void DisplayText(const char* text) override { show(text); }
  void DisplayErrorText(const char* text) override { show(text); }
  void DisplayWarningText(const char* text) override { show(text); }
  void DisplayGenericWarningText(const char* text) override { show(text); }
  void DisplayDebugText(const char* text) override { show(text); }

private:
  static void show(const char* text) {
    if (std::getenv("REPOSE_VERBOSE")) std::cerr << text;
  }
};

}  // namespace

int main(int argc, char** argv) {
  repose::cleanUpOnInterrupt();
  std::signal(SIGXFSZ, SIG_IGN);  // past `ulimit -f` a write fails (EFBIG) and is reported, no core dump
  vtkNew<QuietOutputWindow> quiet;
  vtkOutputWindow::SetInstance(quiet);
  if (!std::getenv("REPOSE_VERBOSE")) vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    std::cout << kMainUsage;
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  if (command == "--version") return std::cout << "repose " << REPOSE_VERSION << "\n", 0;
  try {
    const std::set<std::string> none;
    if (command == "demo")
      return runDemo(Options(argc, argv, 2, {"out", "size", "skinning"}, {"no-render"}), argc, argv);
    if (command == "phantom") return runPhantom(Options(argc, argv, 2, {"out", "size", "rest-pose"}, none));
    if (command == "prepare")
      return runPrepare(Options(argc, argv, 2,
                                {"labels", "skeleton", "image", "out", "body-threshold", "mesh-spacing", "quality",
                                 "influences", "surface-reduction", "label-table", "max-gap", "contact-separation",
                                 "max-tets"},
                                none));
    if (command == "pose")
      return runPose(Options(argc, argv, 2,
                             {"case", "pose", "out", "skinning", "image", "format", "relax-iterations", "relax-model", "relax-volume",
                              "relax-continuation", "relax-strained-region", "poisson",
                              "compare", "mesh", "displacement-field"},
                             {"relax"}),
                     argc, argv);
    if (command == "voxelize") {
      try {
        return repose::runVoxelizeCommand(argc, argv, 2);
      } catch (const repose::VoxelizeUsageError& e) {
        throw UsageError(e.what());
      }
    }
    if (command == "batch") repose::execBatchRunner(argc, argv, 2);  // the Python runner; returns only by throwing
    if (command == "rig") return runRig(Options(argc, argv, 2, {"labels", "label-table", "out", "max-gap"}, none));
    if (command == "animate")
      return runAnimate(Options(argc, argv, 2,
                                {"case", "bvh", "out", "map", "frames", "skinning", "mode", "reference-frame",
                                 "unit-mm", "max-voxels", "image", "relax-iterations", "relax-model", "relax-volume", "relax-continuation",
                                 "relax-strained-region", "poisson", "relax-start", "compare", "mesh", "format"},
                                {"volumes", "no-root-motion", "relax", "strict"}),
                        argc, argv);
    throw UsageError("unknown command '" + command + "' (see repose --help)");
  } catch (const UsageError& e) {
    std::cerr << "repose: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::string msg = repose::withFinalPaths(e.what());
    for (char& c : msg)
      if (c == '\n') c = ' ';
    std::cerr << "repose: error: " << msg << "\n";
    return 1;
  }
}
