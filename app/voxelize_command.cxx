#include "voxelize_command.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <vtkCellArray.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkPoints.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "atomic_outputs.h"
#include "cli_options.h"
#include "output_guard.h"
#include "ReposeMeshConversion.h"
#include "mesh_io.h"
#include "mesh_topology.h"
#include "mesh_voxelizer.h"
#include "repose_pipeline.h"
#include "vtkReposeAutoRig.h"
#include "vtkReposeMeshVoxelizer.h"

namespace repose {

const char* kVoxelizeUsage =
    "usage: repose voxelize --skin MESH --bone NAME=MESH ... [--tissue NAME=MESH ...] [--bones-split PREFIX=MESH ...]\n"
    "                       --voxel MM --out labels.nii.gz [--skeleton-out skeleton.json] [options]\n"
    "  Turns surfaces (.obj, .stl, .ply, .vtp, .vtk) into one label volume: the skin's interior is soft tissue\n"
    "  (label 1), each bone gets its own label (2, 3, ... in the order given), then each tissue; bones win over\n"
    "  tissues over skin. The label table is written beside the output (labels.nii.gz -> labels.tsv, as\n"
    "  'repose prepare --label-table' reads it). The grid is axis-aligned (LPS, identity direction) with cubic\n"
    "  voxels, fitted to the skin's bounds. Mesh coordinates are taken as LPS millimetres (scaled by --unit-mm).\n"
    "  Surfaces are taken as they come: a voxel is inside where the surface's generalized winding number is at\n"
    "  least 1/2, so holes are spanned, overlapping pieces (a hip bone's ilium, ischium and pubis) are united,\n"
    "  inward pieces inside others (a skull's inner table) are carved out and inside-out surfaces turned; each\n"
    "  part's line says what was repaired. A surface too open to have an inside (an open sheet, a dish) is an\n"
    "  error; bones partly outside the skin are kept and reported.\n"
    "  Bones are solid: a hollow a bone's surface walls in (a cortical shell's marrow and cancellous bone, as the\n"
    "  hip bones of atlases come) is filled as bone when the largest ball it holds has a radius of at most\n"
    "  --max-marrow-radius; a wider one (a skull's cranial cavity) stays a cavity. Each bone's line gives its\n"
    "  shell volume (what the surface encloses) and its solid volume.\n"
    "  --skin MESH             the body's outer surface (required)\n"
    "  --skin-name NAME        label name of the skin's interior (default soft_tissue)\n"
    "  --bone NAME=MESH        a bone surface (repeatable); names like hip_left, sacrum, femur_left, patella_left,\n"
    "                          tibia_left, fibula_left, humerus_right let --skeleton-out and 'repose prepare\n"
    "                          --skeleton auto' find the joints\n"
    "  --bones-split PREFIX=MESH  every connected piece of MESH is a bone PREFIX_1, PREFIX_2, ... (file order)\n"
    "  --tissue NAME=MESH      another soft tissue (repeatable), e.g. muscle=muscle.stl\n"
    "  --voxel MM              voxel size (required unless --reference)\n"
    "  --reference IMAGE       use this image's grid (origin, spacing, direction, size) instead\n"
    "  --out FILE              label volume (.nii.gz, .nii, .nrrd, .mha)\n"
    "  --unit-mm MM            millimetres per mesh unit (default 1; e.g. 10 for centimetres)\n"
    "  --padding VOXELS        background voxels around the skin (default 2)\n"
    "  --max-voxels N          largest grid accepted (default 536870912)\n"
    "  --max-marrow-radius MM  widest hollow filled as bone: radius of the largest ball it holds (default 30;\n"
    "                          cancellous bone holds balls of up to about 25 mm, a cranial cavity 50 mm or more)\n"
    "  --hollow-bones          keep bones as their surfaces enclose them: shells stay shells, hollows are reported\n"

    "  --skeleton-out FILE     also build skeleton.json with the automatic rig (see 'repose rig'); it needs\n"
    "                          bones named as the rig knows them (femur_left, tibia_left, hip_left, ...)\n"
    "  --max-gap MM            largest bone gap that still makes a joint, for --skeleton-out (default 6)\n";

namespace {

struct Args {
  std::map<std::string, std::string> single;
  std::vector<std::pair<std::string, std::string>> repeated;  // (option, value) in order
  std::set<std::string> flags;
  bool help = false;
};

Args parse(int argc, char** argv, int first) {
  const std::set<std::string> valued{"skin",    "skin-name",  "voxel",        "reference", "out",
                                     "unit-mm", "padding",    "max-voxels",   "skeleton-out", "max-gap",
                                     "max-marrow-radius"};
  const std::set<std::string> repeatable{"bone", "tissue", "bones-split"};
  const std::set<std::string> flags{"hollow-bones"};
  Args a;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      a.help = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + arg + "'");
    std::string name = arg.substr(2);
    if (flags.count(name)) {
      a.flags.insert(name);
      continue;
    }
    if (!valued.count(name) && !repeatable.count(name)) throw UsageError("unknown option --" + name);
    if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
    const std::string value = argv[++i];
    if (repeatable.count(name))
      a.repeated.emplace_back(name, value);
    else
      a.single[name] = value;
  }
  return a;
}

double number(const Args& a, const std::string& name, double fallback) {
  auto it = a.single.find(name);
  if (it == a.single.end()) return fallback;
  char* end = nullptr;
  const double x = std::strtod(it->second.c_str(), &end);
  if (it->second.empty() || *end != '\0' || !std::isfinite(x))
    throw UsageError("--" + name + " needs a number, not '" + it->second + "'");
  return x;
}

/// "NAME=FILE" -> (NAME, FILE)
std::pair<std::string, std::string> nameAndFile(const std::string& option, const std::string& value) {
  const auto eq = value.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == value.size())
    throw UsageError("--" + option + " needs NAME=MESH, not '" + value + "'");
  return {value.substr(0, eq), value.substr(eq + 1)};
}

/// Reads a surface as a triangle soup scaled to millimetres.
TriangleMesh readTriangles(const std::string& path, double unitMm) {
  vtkSmartPointer<vtkPolyData> mesh = readSurfaceMesh(path);
  TriangleMesh m;
  m.V = unitMm * repose_vtk::ToPoints(mesh->GetPoints());
  m.F = repose_vtk::ToTriangleFans(mesh);
  if (m.F.rows() == 0) throw std::runtime_error(path + ": has no triangles");
  return m;
}

/// The triangles as the voxelizer filter takes them (double points, so nothing is rounded).
vtkSmartPointer<vtkPolyData> toPolyData(const TriangleMesh& m) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(m.V.rows());
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) points->SetPoint(i, m.V(i, 0), m.V(i, 1), m.V(i, 2));
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const vtkIdType ids[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
    polys->InsertNextCell(3, ids);
  }
  auto mesh = vtkSmartPointer<vtkPolyData>::New();
  mesh->SetPoints(points);
  mesh->SetPolys(polys);
  return mesh;
}

/// One input of the voxelizer filter: its surface, label name, role and source (for messages).
void addPart(vtkReposeMeshVoxelizer* voxelizer, const TriangleMesh& mesh, const std::string& name, int role,
             const std::string& source) {
  const int index = voxelizer->GetNumberOfInputConnections(0);
  voxelizer->AddInputData(0, toPolyData(mesh));
  voxelizer->SetPartName(index, name.c_str());
  voxelizer->SetPartRole(index, role);
  voxelizer->SetPartSource(index, source.c_str());
}

/// labels.nii.gz -> labels.tsv beside it.
std::string tablePathFor(const std::string& out) {
  const std::string ext = imageExtension(out);
  return out.substr(0, out.size() - ext.size()) + ".tsv";
}

/// The image, its label table and the skeleton must not replace a mesh or the reference read.
void refuseOutputsOverOwnInputs(const Args& a, const std::string& outPath) {
  namespace fs = std::filesystem;
  CommandInputs inputs;
  for (const char* n : {"skin", "reference"})
    if (a.single.count(n)) inputs.files.push_back(a.single.at(n));
  for (const auto& [option, value] : a.repeated) inputs.files.push_back(value.substr(value.find('=') + 1));
  auto check = [&](const fs::path& file, std::vector<std::string> names) {
    refuseOutputsOverInputs(file.has_parent_path() ? file.parent_path().string() : ".", names, inputs);
  };
  const fs::path out(outPath);
  check(out, {out.filename().string(), fs::path(tablePathFor(outPath)).filename().string()});
  if (a.single.count("skeleton-out")) check(a.single.at("skeleton-out"), {fs::path(a.single.at("skeleton-out")).filename().string()});
}

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int runVoxelizeCommand(int argc, char** argv, int first) {
  const Args a = parse(argc, argv, first);
  if (a.help) return std::cout << kVoxelizeUsage, 0;
  auto require = [&](const std::string& n) {
    auto it = a.single.find(n);
    if (it == a.single.end() || it->second.empty()) throw UsageError("missing required option --" + n);
    return it->second;
  };
  const std::string skinPath = require("skin");
  const std::string outPath = require("out");
  const std::string ext = imageExtension(outPath);
  if (ext != ".nii.gz" && ext != ".nii" && ext != ".nrrd" && ext != ".mha" && ext != ".mhd" && ext != ".nhdr")
    throw UsageError("--out needs an image file name (.nii.gz, .nii, .nrrd, .mha), not '" + outPath + "'");
  const bool hasReference = a.single.count("reference") != 0;
  refuseOutputsOverOwnInputs(a, outPath);
  if (!hasReference && !a.single.count("voxel")) throw UsageError("missing required option --voxel (or --reference)");
  const double unitMm = number(a, "unit-mm", 1.0);
  if (!(unitMm > 0)) throw UsageError("--unit-mm must be positive");
  LabelVoxelizeOptions options;
  options.voxelMm = number(a, "voxel", 1.0);
  options.padVoxels = number(a, "padding", 2.0);
  const double maxVoxels = number(a, "max-voxels", double(options.maxVoxels));
  if (!(options.voxelMm > 0)) throw UsageError("--voxel must be positive");
  if (options.padVoxels < 0) throw UsageError("--padding must not be negative");
  if (!(maxVoxels >= 1)) throw UsageError("--max-voxels must be at least 1");
  options.maxVoxels = std::size_t(maxVoxels);
  options.maxMarrowRadiusMm = number(a, "max-marrow-radius", kMaxMarrowRadiusMm);
  if (!(options.maxMarrowRadiusMm >= 0)) throw UsageError("--max-marrow-radius must not be negative");
  options.hollowBones = a.flags.count("hollow-bones") != 0;
  const double maxGap = number(a, "max-gap", 6.0);
  for (const auto& [opt, value] : a.repeated) nameAndFile(opt, value);  // usage errors before any reading

  const auto t0 = std::chrono::steady_clock::now();
  auto voxelizer = vtkSmartPointer<vtkReposeMeshVoxelizer>::New();
  voxelizer->SetVoxelSize(options.voxelMm);
  voxelizer->SetPaddingVoxels(options.padVoxels);
  voxelizer->SetMaxVoxels(double(options.maxVoxels));
  voxelizer->SetMaxMarrowRadius(options.maxMarrowRadiusMm);
  voxelizer->SetHollowBones(options.hollowBones);
  addPart(voxelizer, readTriangles(skinPath, unitMm), a.single.count("skin-name") ? a.single.at("skin-name") : "soft_tissue",
          vtkReposeMeshVoxelizer::Skin, skinPath);
  for (const auto& [opt, value] : a.repeated) {
    const auto [name, file] = nameAndFile(opt, value);
    TriangleMesh m = readTriangles(file, unitMm);
    if (opt == "bones-split") {
      std::vector<TriangleMesh> pieces;
      try {
        pieces = splitConnectedComponents(m.V, m.F);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(file + ": " + e.what());
      }
      for (std::size_t i = 0; i < pieces.size(); ++i)
        addPart(voxelizer, pieces[i], name + "_" + std::to_string(i + 1), vtkReposeMeshVoxelizer::Bone,
                file + " (piece " + std::to_string(i + 1) + " of " + std::to_string(pieces.size()) + ")");
      std::cout << "voxelize: " << file << ": " << pieces.size() << " pieces, bones " << name << "_1.." << name << "_"
                << pieces.size() << "\n";
      continue;
    }
    addPart(voxelizer, m, name, opt == "bone" ? vtkReposeMeshVoxelizer::Bone : vtkReposeMeshVoxelizer::Tissue, file);
  }
  const double readSeconds = seconds(t0);

  if (hasReference) voxelizer->SetReferenceImage(readIntensityImage(a.single.at("reference")));
  // The voxelizer's messages name the surface at fault.
  if (const auto error = updateFilter(voxelizer))
    throw std::runtime_error(error->empty() ? outPath + ": voxelizing failed" : *error);
  std::cout << "voxelize: " << voxelizer->GetReport();
  const double voxelizeSeconds = voxelizer->GetSeconds();

  vtkSmartPointer<vtkImageData> labels = vtkSmartPointer<vtkImageData>::New();
  labels->ShallowCopy(voxelizer->GetOutput());
  std::string tableTsv = voxelizer->GetLabelTableTSV();
  voxelizer = nullptr;  // the labels image holds the only copy of the voxels from here on
  std::string skeletonJson;
  if (a.single.count("skeleton-out")) {
    auto rig = vtkSmartPointer<vtkReposeAutoRig>::New();
    rig->SetInputData(labels);
    rig->SetLabelTableTSV(tableTsv.c_str());
    rig->SetLabelTableName("the voxelized surfaces' names");
    rig->SetMaxGapMm(maxGap);
    updateOrThrowFor(rig, outPath, "automatic skeleton");
    std::cout << rig->GetReport();
    if (rig->GetNumberOfJoints() < 2)
      throw std::runtime_error(outPath + ": the automatic skeleton found " + std::to_string(rig->GetNumberOfJoints()) +
                               " joint(s): name the bones as the rig knows them (femur_left, tibia_left, hip_left, "
                               "humerus_right, ...) or write skeleton.json by hand");
    labels = vtkSmartPointer<vtkImageData>::New();
    labels->ShallowCopy(rig->GetOutput());
    tableTsv = rig->GetOutputLabelTableTSV();
    skeletonJson = rig->GetSkeletonJSON();
  }
  int dims[3];
  labels->GetDimensions(dims);

  // Both outputs staged, then moved into place together.
  const std::filesystem::path out(outPath);
  AtomicOutputs files(out.has_parent_path() ? out.parent_path().string() : ".");
  writeLabelImage(labels, files.stage(out.filename().string()));
  labels = nullptr;
  writeTextFile(files.stage(std::filesystem::path(tablePathFor(outPath)).filename().string()), tableTsv);
  std::unique_ptr<AtomicOutputs> skeletonFiles;  // only when the skeleton goes to another folder
  if (!skeletonJson.empty()) {
    namespace fs = std::filesystem;
    const fs::path s(a.single.at("skeleton-out"));
    const fs::path sdir = s.has_parent_path() ? s.parent_path() : fs::path(".");
    const fs::path odir = out.has_parent_path() ? out.parent_path() : fs::path(".");
    AtomicOutputs* target = &files;
    if (fs::weakly_canonical(sdir) != fs::weakly_canonical(odir)) {
      skeletonFiles = std::make_unique<AtomicOutputs>(sdir.string());
      target = skeletonFiles.get();
    }
    writeTextFile(target->stage(s.filename().string()), skeletonJson);
  }
  files.commit();
  if (skeletonFiles) skeletonFiles->commit();
  std::cout << "voxelize: " << dims[0] << "x" << dims[1] << "x" << dims[2]
            << " voxels written to " << outPath << " and " << tablePathFor(outPath)
            << (skeletonJson.empty() ? std::string() : " (skeleton: " + a.single.at("skeleton-out") + ")")
            << "; reading " << readSeconds << " s, voxelizing " << voxelizeSeconds << " s\n";
  return 0;
}

}  // namespace repose
