#include "pose_command.h"

#include <chrono>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "ReposeImageConversion.h"
#include "atomic_outputs.h"
#include "cli_options.h"
#include "console_progress.h"
#include "display_requirement.h"
#include "fidelity_report.h"
#include "mesh_binding.h"
#include "mesh_io.h"
#include "output_guard.h"
#include "pipeline_report.h"
#include "posed_writes.h"
#include "relaxation_options.h"
#include "repose_pipeline.h"
#include "vdb_volume_writer.h"
#include "volume_format_option.h"

namespace repose {
namespace {

const char* kPoseUsage =
    "usage: repose pose --case CASE_DIR --pose FILE --out DIR [--skinning dqs|lbs] [--image FILE] [--format EXT]\n"
    "                   [--mesh FILE ...] [--relax [--relax-model M] [--poisson NU]] [--compare lbs,dqs,dqs+fem]\n"
    "                   [--displacement-field NAME]\n"
    "  Writes DIR/posed_labels<ext> with its names and colours beside it (posed_labels.tsv, and\n"
    "  posed_labels.ctbl for 3D Slicer), DIR/posed_mesh.vtu, DIR/posed_surfaces.vtp and, with --image,\n"
    "  DIR/posed_image<ext of the image>. --format (.nii.gz, .nii, .nrrd, .mha, .mhd) sets the label\n"
    "  volume's format; default: the format of the case's labels. --format vti writes both volumes as VTK XML\n"
    "  image data with their direction matrix: ParaView opens them lined up with posed_mesh.vtu\n"
    "  --format seg.nrrd       DIR/posed_labels.seg.nrrd, a 3D Slicer segmentation: a segment per label, named and\n"
    "                          coloured from the case's label table (the posed image keeps its own format)\n"
    "  --image FILE            a CT/MRI on the case's label grid; a folder is read as a DICOM CT series\n"
    "                          (--series-uid UID when it holds several) and the posed CT written as one\n"
    "                          (DIR/posed_image/: a new series in the same study, image type DERIVED)\n"
    "  --format dicom          DICOM for clinical systems: DIR/posed_labels.dcm, a DICOM Segmentation with a\n"
    "                          segment per label (its name, colour, bone or tissue), and with --image the posed CT\n"
    "                          as a DICOM series DIR/posed_image/, both in one study and frame of reference (the\n"
    "                          CT's when it was DICOM, else a new one with an anonymous patient)\n"
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

/// Each --mesh posed and written as posed_<its file name>, with its posing time on stdout.
void writePosedMeshes(Pipeline& pipeline, const MeshPoser& poser, AtomicOutputs& out) {
  for (std::size_t i = 0; i < poser.meshes().size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    vtkSmartPointer<vtkPolyData> posed = poser.pose(i, pipeline.posedMesh());
    const double ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string name = posedMeshName(poser.meshes()[i].path);
    writeSurfaceMesh(posed, out.stage(name));
    std::cout << "mesh " << poser.meshes()[i].path << ": posed in " << std::fixed << std::setprecision(1) << ms
              << " ms -> " << name << "\n";
    std::cout.unsetf(std::ios::floatfield);
  }
}

/// --format vdb: the posed label volume (and image) as sparse OpenVDB grids.
void writePosedVdb(Pipeline& pipeline, AtomicOutputs& out, double imageBackground) {
  auto describe = [](const std::string& name, const VdbWriteReport& r, std::size_t voxels, std::size_t bytes) {
    std::cout << "vdb " << name << ": " << r.grids << " grid(s), " << r.activeVoxels << " of " << voxels
              << " voxels active (" << std::fixed << std::setprecision(1) << 100.0 * double(r.activeVoxels) / double(voxels)
              << " %), " << double(r.memoryBytes) / 1e6 << " MB sparse vs " << double(bytes) / 1e6
              << " MB dense, built in " << std::setprecision(3) << r.buildSeconds << " s, written in " << r.writeSeconds
              << " s\n";
    std::cout.unsetf(std::ios::floatfield);
  };
  LabelVolume labels;
  if (!repose_vtk::ToVolume(pipeline.posedLabels(), labels)) throw std::runtime_error("posed labels: not a volume");
  const VdbWriteReport r = writeLabelsVdb(labels, out.stage("posed_labels.vdb"));
  describe("posed_labels.vdb", r, labels.data.size(), labels.data.size() * sizeof(std::int32_t));
  if (vtkImageData* image = pipeline.posedImage()) {
    IntensityVolume ct;
    if (!repose_vtk::ToVolume(image, ct)) throw std::runtime_error("posed image: not a volume");
    const VdbWriteReport ri =
        writeIntensityVdb(ct, static_cast<float>(imageBackground), out.stage("posed_image.vdb"), "ct");
    describe("posed_image.vdb", ri, ct.data.size(), ct.data.size() * sizeof(float));
  }
}

/// Every file `pose` may write (each format's posed volumes), so that none can replace an input.
std::vector<std::string> poseOutputNames(const std::vector<std::string>& meshes) {
  std::vector<std::string> names = {"posed_mesh.vtu", "posed_surfaces.vtp", "fidelity.csv", "fidelity.png"};
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".raw.gz", ".mha", ".mhd", ".raw", ".zraw", ".vdb", ".dcm", ".seg.nrrd", ""})
    for (const char* stem : {"posed_labels", "posed_image"}) names.push_back(stem + std::string(ext));
  for (const std::string& mesh : meshes) names.push_back(posedMeshName(mesh));
  return names;
}

}  // namespace

int runPoseCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first,
                  {"case", "pose", "out", "skinning", "image", "series-uid", "format", "relax-iterations", "relax-model",
                   "relax-volume", "relax-continuation", "relax-strained-region", "poisson", "compare", "mesh",
                   "displacement-field"},
                  {"relax"});
  if (o.help) return std::cout << kPoseUsage, 0;
  if (o.has("compare")) requireDisplay(argc, argv, "fidelity.png");
  const std::string caseDir = o.require("case");
  const std::string posePath = o.require("pose");
  const std::string outDir = o.require("out");
  refuseOutputsOverInputs(outDir, poseOutputNames(o.all("mesh")), {inputFiles(o, {"pose", "image"}), {caseDir}});
  Pipeline pipeline;
  pipeline.setProgress(throttledConsoleProgress("pose: "));
  pipeline.loadCase(caseDir);
  pipeline.setPose(readTextFile(posePath), posePath);
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  const RelaxationChoice relaxation = applyRelaxation(pipeline, o);
  std::string imageExt = ".nii.gz";
  double imageBackground = 0;
  if (o.has("image")) {
    const std::string imagePath = o.get("image");
    vtkSmartPointer<vtkImageData> image = readIntensityImage(imagePath, o.get("series-uid"));
    pipeline.setRestImage(image, imagePath);
    imageExt = imageExtension(imagePath);
    double range[2];
    image->GetPointData()->GetScalars()->GetRange(range);
    imageBackground = range[0];  // the posed image's air outside the body (see Pipeline::setRestImage)
  }
  const bool vdb = isVdbFormat(o.get("format"));
  const bool dicom = o.get("format") == "dicom";
  const std::string labelsExt = vdb ? ".vdb"
                                : dicom ? ".dcm"
                                : o.has("format") ? normalizedLabelFormat(o.get("format"))
                                                  : pipeline.labelsExtension();
  if (dicom) imageExt = "/";  // the posed CT as a DICOM series
  if (labelsExt == ".vti") imageExt = ".vti";  // for ParaView, the CT too
  const std::vector<std::string> compare = parseCompare(o);
  const std::string displacementName = o.has("displacement-field") ? displacementFileName(o.get("displacement-field")) : "";
  std::unique_ptr<MeshPoser> meshes = bindMeshes(pipeline, o, caseDir);
  AtomicOutputs out(outDir);
  if (vdb) {
    writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
    writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
    writePosedVdb(pipeline, out, imageBackground);
    writeLabelTables(pipeline, out, "posed_labels");
  } else if (dicom) {
    writePosedDicom(pipeline, out);
  } else {
    writePosed(pipeline, out, labelsExt, imageExt);
  }
  if (meshes) writePosedMeshes(pipeline, *meshes, out);
  if (!displacementName.empty()) writeImage(pipeline.posedDisplacement(), out.stage(displacementName));
  if (!compare.empty()) {
    FidelityReport fidelity;
    fidelity.methods = compare;
    fidelity.addFrame(pipeline, 0, o.get("skinning", "dqs"), relaxation.enabled, relaxation.poisson,
                      relaxation.iterations);
    fidelity.write(out);
  }
  const PoseQuality quality = poseQualityOf(pipeline, pipeline.posedStats());
  out.commit();
  if (o.has("relax")) std::cout << pipeline.relaxationSummary() << "\n";
  std::cout << "posed outputs written to " << outDir << "\n";
  std::cout << "quality: " << quality.summary << "\n";
  for (const std::string& w : quality.warnings) std::cerr << "warning: " << w << "\n";
  printTimings(pipeline);
  return 0;
}

}  // namespace repose
