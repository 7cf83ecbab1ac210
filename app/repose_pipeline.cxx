#include "repose_pipeline.h"

#include <optional>

#include "mesh_file_claims.h"
#include "mesh_io.h"
#include "json_text.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <json/json.h>

#include <vtkAlgorithm.h>
#include <vtkCommand.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkPoints.h>
#include <vtkIntArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "ReposeMeshConversion.h"
#include "vtkReposeBodyMesher.h"
#include "vtkReposeCorotationalRelax.h"
#include "vtkReposeDicomSeriesWriter.h"
#include "repose_version.h"
#include "vtkReposeBoneWeights.h"
#include "vtkReposeImageReader.h"
#include "vtkReposeImageWriter.h"
#include "vtkReposePosedVolume.h"
#include "vtkReposeSkinning.h"
#include "vtkReposeSurfaceBinding.h"
#include "vtkReposeSurfaceDeformer.h"
#include "vtkReposeSurfaceExtractor.h"

#include "atomic_outputs.h"
#include "checked_write.h"
#include "pose.h"
#include "skeleton.h"
#include "deformation_stats.h"
#include "pose_quality.h"
#include "label_table.h"
#include "tet_mesh.h"
#include "array_names.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

vtkSmartPointer<vtkImageData> readImageFile(const std::string& path, const std::string& seriesUid = "") {
  if (!fileExists(path)) throw std::runtime_error(path + ": no such file");
  auto reader = vtkSmartPointer<vtkReposeImageReader>::New();
  reader->SetFileName(path.c_str());
  if (!seriesUid.empty()) reader->SetSeriesUID(seriesUid.c_str());
  reader->Update();
  if (reader->GetLastError() && *reader->GetLastError())
    throw std::runtime_error(reader->GetLastError());
  vtkImageData* out = reader->GetOutput();
  if (!out || !out->GetPointData()->GetScalars())
    throw std::runtime_error(path + ": cannot read image");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->ShallowCopy(out);
  return image;
}

/// Records the last error a VTK filter reported through vtkErrorMacro (the core's message), so it
/// can be shown to the user as one line instead of VTK's multi-line console text.
class ErrorCapture : public vtkCommand {
public:
  static ErrorCapture* New() { return new ErrorCapture; }
  void Execute(vtkObject*, unsigned long, void* callData) override {
    std::string text = callData ? static_cast<const char*>(callData) : "";
    const auto pos = text.find("): ");
    if (pos != std::string::npos) text = text.substr(pos + 3);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    for (char& c : text)
      if (c == '\n') c = ' ';
    last = text;
  }
  std::string last;
};

vtkSmartPointer<ErrorCapture> captureErrors(vtkAlgorithm* filter) {
  auto capture = vtkSmartPointer<ErrorCapture>::New();
  filter->AddObserver(vtkCommand::ErrorEvent, capture);
  return capture;
}

/// Checks a filter ran; the filters report core errors through vtkErrorMacro and an empty output.
void requireOutput(bool ok, const std::string& what, const ErrorCapture* errors) {
  if (!ok)
    throw std::runtime_error(what + " failed" + (errors && !errors->last.empty() ? ": " + errors->last : std::string()));
}

std::string describeGrid(vtkImageData* image) {
  int d[3];
  double o[3], s[3];
  image->GetDimensions(d);
  image->GetOrigin(o);
  image->GetSpacing(s);
  std::ostringstream m;
  m << d[0] << "x" << d[1] << "x" << d[2] << " voxels of " << s[0] << "x" << s[1] << "x" << s[2]
    << " mm at (" << o[0] << ", " << o[1] << ", " << o[2] << ")";
  return m.str();
}


constexpr int kCaseVersion = 1;

/// A JSON value as a short one-line text for messages.
std::string brief(const Json::Value& value) {
  Json::StreamWriterBuilder builder;
  builder["indentation"] = "";
  const std::string text = Json::writeString(builder, value);
  return text.size() > 40 ? text.substr(0, 40) + "..." : text;
}

/// A file named by the case manifest: a plain name inside the case folder, never a path leaving it.
std::string caseFile(const std::string& caseDir, const Json::Value& manifest, const char* key,
                     const std::string& manifestPath) {
  const Json::Value& name = manifest[key];
  const std::string text = name.isString() ? name.asString() : std::string();
  if (text.empty() || text == "." || text == ".." || text.find_first_of("/\\") != std::string::npos)
    throw std::runtime_error(manifestPath + ": \"" + key + "\" must name a file inside the case folder, not '" +
                             (name.isString() ? text : brief(name)) + "'");
  return caseDir + "/" + text;
}

/// Reads a VTK XML file, its claims checked first; errors name the file on one line.
template <class Reader>
vtkSmartPointer<vtkPointSet> readXmlMesh(const std::string& path) {
  try {
    checkMeshFileClaims(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  auto reader = vtkSmartPointer<Reader>::New();
  reader->SetFileName(path.c_str());
  auto errors = captureErrors(reader);
  reader->Update();
  vtkPointSet* out = vtkPointSet::SafeDownCast(reader->GetOutputDataObject(0));
  if (!errors->last.empty() || !out || out->GetNumberOfPoints() == 0)
    throw std::runtime_error(path + ": cannot read (" + (errors->last.empty() ? "no points" : errors->last) + ")");
  try {
    checkMeshContents(out);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  vtkSmartPointer<vtkPointSet> copy;
  copy.TakeReference(out->NewInstance());
  copy->ShallowCopy(out);
  return copy;
}

/// The array `name` of `data` with `components` components and `tuples` tuples, or an error.
vtkDataArray* caseArray(vtkFieldData* data, const char* name, int components, vtkIdType tuples,
                        const std::string& path) {
  vtkDataArray* a = vtkDataArray::SafeDownCast(data->GetAbstractArray(name));
  if (!a || a->GetNumberOfComponents() != components || a->GetNumberOfTuples() != tuples)
    throw std::runtime_error(path + ": array " + name + " is missing or not " + std::to_string(tuples) + " x " +
                             std::to_string(components) + " (not a prepared case file, or a damaged one)");
  return a;
}

std::string shortNumber(double v) {
  std::ostringstream text;
  text << v;
  return text.str();
}

/// Every value of `a` finite and, when lo <= hi, within [lo, hi].
void requireValues(vtkDataArray* a, double lo, double hi, const std::string& path) {
  for (vtkIdType i = 0, n = a->GetNumberOfTuples(); i < n; ++i)
    for (int c = 0; c < a->GetNumberOfComponents(); ++c) {
      const double v = a->GetComponent(i, c);
      if (!std::isfinite(v) || (lo <= hi && (v < lo || v > hi)))
        throw std::runtime_error(path + ": array " + a->GetName() + " holds " + shortNumber(v) + " at tuple " +
                                 std::to_string(i) + (lo <= hi ? " (expected " + std::to_string(int(lo)) + ".." +
                                                                     std::to_string(int(hi)) + ")"
                                                               : std::string(" (not finite)")));
    }
}

vtkSmartPointer<vtkUnstructuredGrid> readCaseMesh(const std::string& path, const Json::Value& manifest,
                                                  const std::string& manifestPath, const Skeleton& skeleton) {
  auto mesh = vtkSmartPointer<vtkUnstructuredGrid>::New();
  mesh->ShallowCopy(readXmlMesh<vtkXMLUnstructuredGridReader>(path));
  if (!manifest["nodes"].isIntegral() || manifest["nodes"].asLargestInt() != mesh->GetNumberOfPoints() ||
      !manifest["tets"].isIntegral() || manifest["tets"].asLargestInt() != mesh->GetNumberOfCells())
    throw std::runtime_error(manifestPath + ": says " + brief(manifest["nodes"]) +
                             " nodes and " + brief(manifest["tets"]) + " tets, " + path +
                             " has " + std::to_string(mesh->GetNumberOfPoints()) + " and " +
                             std::to_string(mesh->GetNumberOfCells()));
  for (vtkIdType c = 0, n = mesh->GetNumberOfCells(); c < n; ++c)
    if (mesh->GetCellType(c) != VTK_TETRA)
      throw std::runtime_error(path + ": cell " + std::to_string(c) + " is not a tetrahedron");
  const vtkIdType nodes = mesh->GetNumberOfPoints();
  vtkDataArray* weights = vtkDataArray::SafeDownCast(mesh->GetPointData()->GetAbstractArray(repose::arrays::kWeights));
  const int influences = weights ? weights->GetNumberOfComponents() : 1;
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kWeights, influences, nodes, path), 0, -1, path);
  const double lastBone = double(skeleton.joints.size()) - 1;
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kBoneIds, influences, nodes, path), 0, lastBone, path);
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kFixedBone, 1, nodes, path), -1, lastBone, path);
  return mesh;
}

vtkSmartPointer<vtkPolyData> readCaseSurfaces(const std::string& path, vtkIdType tets) {
  auto surfaces = vtkSmartPointer<vtkPolyData>::New();
  surfaces->ShallowCopy(readXmlMesh<vtkXMLPolyDataReader>(path));
  const vtkIdType n = surfaces->GetNumberOfPoints();
  requireValues(caseArray(surfaces->GetPointData(), repose::arrays::kBoundTet, 1, n, path), 0, double(tets) - 1, path);
  requireValues(caseArray(surfaces->GetPointData(), repose::arrays::kBoundWeights, 4, n, path), 0, -1, path);
  if (!vtkIntArray::SafeDownCast(surfaces->GetPointData()->GetArray(repose::arrays::kBoundTet)) ||
      !vtkFloatArray::SafeDownCast(surfaces->GetPointData()->GetArray(repose::arrays::kBoundWeights)))
    throw std::runtime_error(path + ": BoundTet must be int32 and BoundWeights float32");
  return surfaces;
}

/// The tet mesh was made from the label volume: its nodes lie within the volume's box, give or take
/// the meshing grid's coarser voxels (a quarter of the box, and three voxels, of margin). A case
/// whose labels lie elsewhere than its mesh (another scan's, or a moved grid) is refused.
void checkMeshOnGrid(vtkPointSet* mesh, const std::string& meshPath, vtkImageData* labels,
                     const std::string& labelsPath) {
  int dims[3];
  double spacing[3];
  labels->GetDimensions(dims);
  labels->GetSpacing(spacing);
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int corner = 0; corner < 8; ++corner) {
    const double ijk[3] = {corner & 1 ? dims[0] - 1.0 : 0.0, corner & 2 ? dims[1] - 1.0 : 0.0,
                           corner & 4 ? dims[2] - 1.0 : 0.0};
    double xyz[3];
    labels->TransformContinuousIndexToPhysicalPoint(ijk, xyz);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], xyz[a]), hi[a] = std::max(hi[a], xyz[a]);
  }
  const double margin = 0.25 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) +
                        3 * std::max({spacing[0], spacing[1], spacing[2]});
  double b[6];
  mesh->GetBounds(b);
  for (int a = 0; a < 3; ++a)
    if (b[2 * a] < lo[a] - margin || b[2 * a + 1] > hi[a] + margin)
      throw std::runtime_error(labelsPath + ": its grid (" + describeGrid(labels) + ") does not hold " + meshPath +
                               " (the case's labels and mesh come from different scans)");
}
}  // namespace

vtkSmartPointer<vtkImageData> readLabelVolume(const std::string& path) {
  // A folder would be read as a DICOM CT series and its outputs written as one: labels are files.
  if (std::filesystem::is_directory(path))
    throw std::runtime_error(path + ": a folder; label volumes are read from files (NIfTI, NRRD, MetaImage)");
  vtkSmartPointer<vtkImageData> image = readImageFile(path);
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (scalars->GetNumberOfComponents() != 1)
    throw std::runtime_error(path + ": label volume must have one component per voxel, not " +
                             std::to_string(scalars->GetNumberOfComponents()));
  if (scalars->GetDataType() != VTK_INT) {
    // Float files holding whole numbers are common for label maps; anything else is not a label map.
    const vtkIdType n = scalars->GetNumberOfTuples();
    auto labels = vtkSmartPointer<vtkIntArray>::New();
    labels->SetName(repose::arrays::kLabels);
    labels->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) {
      const double v = scalars->GetTuple1(i);
      if (!std::isfinite(v) || v != std::floor(v) || std::fabs(v) > 2147483647.0)
        throw std::runtime_error(path + ": not a label volume (voxel value " + std::to_string(v) +
                                 " is not an integer)");
      labels->SetValue(i, static_cast<int>(v));
    }
    image->GetPointData()->SetScalars(labels);
  }
  vtkIntArray* labels = vtkIntArray::SafeDownCast(image->GetPointData()->GetScalars());
  labels->SetName(repose::arrays::kLabels);
  // Tables indexed by label value are sized by the largest label: bound it before anyone allocates.
  bool any = false;
  for (vtkIdType i = 0, n = labels->GetNumberOfTuples(); i < n; ++i) {
    const int v = labels->GetValue(i);
    if (v < 0 || v > kMaxLabelValue)
      throw std::runtime_error(path + ": label " + std::to_string(v) + " is outside 0.." +
                               std::to_string(kMaxLabelValue) + " (not a label volume, or a damaged one)");
    any = any || v != 0;
  }
  if (!any) throw std::runtime_error(path + ": empty label volume (every voxel is 0)");
  return image;
}

vtkSmartPointer<vtkImageData> readIntensityImage(const std::string& path, const std::string& seriesUid) {
  vtkSmartPointer<vtkImageData> image = readImageFile(path, seriesUid);
  if (image->GetPointData()->GetScalars()->GetNumberOfComponents() != 1)
    throw std::runtime_error(path + ": image must have one component per voxel");
  return image;
}

namespace {
void writeImageAs(vtkImageData* image, const std::string& path, bool smallestIntegerType) {
  const QuietStderr quiet;
  auto writer = vtkSmartPointer<vtkReposeImageWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetSmallestIntegerType(smallestIntegerType);
  writer->SetInputData(image);
  if (!writer->Write()) {
    const char* err = writer->GetLastError();
    throw std::runtime_error(err && *err ? std::string(err) : path + ": cannot write image");
  }
}
}  // namespace

void writeImage(vtkImageData* image, const std::string& path) {
  if (!path.empty() && path.back() == '/') {  // a DICOM CT series, as the input was
    const QuietStderr quiet;
    auto writer = vtkSmartPointer<vtkReposeDicomSeriesWriter>::New();
    writer->SetFileName(path.substr(0, path.size() - 1).c_str());
    writer->SetSeriesDescription("Reposed (Repose " REPOSE_VERSION ")");
    writer->SetInputData(image);
    if (!writer->Write()) throw std::runtime_error(writer->GetLastError());
    return;
  }
  writeImageAs(image, path, false);
}

void writeLabelImage(vtkImageData* labels, const std::string& path) { writeImageAs(labels, path, true); }

void writeMesh(vtkUnstructuredGrid* mesh, const std::string& path) {
  auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputData(withVersion(mesh));
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writeChecked(writer.Get(), path, kVtkXmlTail);
}

void writeSurfaces(vtkPolyData* surfaces, const std::string& path) {
  auto writer = vtkSmartPointer<vtkXMLPolyDataWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputData(withVersion(surfaces));
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writeChecked(writer.Get(), path, kVtkXmlTail);
}

void checkSameGrid(vtkImageData* labels, const std::string& labelsName, vtkImageData* image,
                   const std::string& imageName) {
  int dl[3], di[3];
  double ol[3], oi[3], sl[3], si[3];
  labels->GetDimensions(dl);
  image->GetDimensions(di);
  labels->GetOrigin(ol);
  image->GetOrigin(oi);
  labels->GetSpacing(sl);
  image->GetSpacing(si);
  bool same = dl[0] == di[0] && dl[1] == di[1] && dl[2] == di[2];
  for (int a = 0; a < 3 && same; ++a)
    same = std::fabs(ol[a] - oi[a]) <= 1e-4 * std::max(1.0, std::fabs(sl[a])) &&
           std::fabs(sl[a] - si[a]) <= 1e-6 * std::fabs(sl[a]);
  for (int r = 0; r < 3 && same; ++r)
    for (int c = 0; c < 3 && same; ++c)
      same = std::fabs(labels->GetDirectionMatrix()->GetElement(r, c) -
                       image->GetDirectionMatrix()->GetElement(r, c)) <= 1e-6;
  if (!same)
    throw std::runtime_error(imageName + " and " + labelsName + " are on different grids (" +
                             describeGrid(image) + " vs " + describeGrid(labels) + ")");
}

std::optional<std::string> updateFilter(vtkAlgorithm* filter) {
  auto capture = vtkSmartPointer<ErrorCapture>::New();
  const unsigned long tag = filter->AddObserver(vtkCommand::ErrorEvent, capture);
  const int ok = filter->GetExecutive()->Update();
  filter->RemoveObserver(tag);
  if (ok && capture->last.empty()) return std::nullopt;
  return capture->last;
}

void updateOrThrow(vtkAlgorithm* filter, const std::string& what) {
  if (const auto error = updateFilter(filter))
    throw std::runtime_error(what + " failed" + (error->empty() ? std::string() : ": " + *error));
}

void updateOrThrowFor(vtkAlgorithm* filter, const std::string& file, const std::string& what) {
  if (const auto error = updateFilter(filter))
    throw std::runtime_error(file + ": " + what + (error->empty() ? std::string(" failed") : " (" + *error + ")"));
}

Pipeline::Pipeline() = default;
Pipeline::~Pipeline() = default;

void Pipeline::note(const std::string& stage) {
  if (cancel_ && cancel_()) throw Cancelled();
  if (progress_) progress_(stage);
}

void Pipeline::forwardProgressText(vtkObject* caller, unsigned long, void*) {
  const char* text = vtkAlgorithm::SafeDownCast(caller) ? vtkAlgorithm::SafeDownCast(caller)->GetProgressText() : nullptr;
  if (progress_ && text && *text) progress_(text);
}

void Pipeline::timed(const std::string& stage, double seconds) { timings_.push_back({stage, seconds}); }

void Pipeline::prepare(vtkImageData* labels, const std::string& labelsName, const std::string& skeletonJson,
                       const std::string& skeletonName, vtkImageData* image, const std::string& imageName,
                       const PrepareSettings& settings) {
  Skeleton skeleton;
  try {
    skeleton = parseSkeletonJson(skeletonJson);
  } catch (const std::exception& e) {
    throw std::runtime_error(skeletonName + ": " + e.what());
  }
  if (skeleton.joints.empty()) throw std::runtime_error(skeletonName + ": skeleton has no joints");
  if (image) checkSameGrid(labels, labelsName, image, imageName);

  // Every bone label must be present: a bone without voxels cannot carry weights.
  std::set<int> present;
  vtkIntArray* values = vtkIntArray::SafeDownCast(labels->GetPointData()->GetScalars());
  if (!values) throw std::runtime_error(labelsName + ": label volume must hold integers");
  for (vtkIdType i = 0, n = values->GetNumberOfTuples(); i < n; ++i) present.insert(values->GetValue(i));
  for (const Joint& joint : skeleton.joints) {
    if (joint.labels.empty())
      throw std::runtime_error(skeletonName + ": joint '" + joint.name + "' lists no labels (its bone has no voxels)");
    for (int label : joint.labels) {
      // Damage to the volume removes a bone as surely as a typo in the skeleton: name the volume.
      if (!present.count(label))
        throw std::runtime_error(labelsName + ": label " + std::to_string(label) + " of joint '" + joint.name +
                                 "' in " + skeletonName + " is absent from the volume");
    }
  }

  restLabels_ = labels;
  restImage_ = nullptr;
  skeletonJson_ = skeletonToJson(skeleton);
  report_.clear();

  note("meshing the body (TetGen)");
  auto t0 = Clock::now();
  auto mesher = vtkSmartPointer<vtkReposeBodyMesher>::New();
  mesher->SetInputData(0, labels);
  if (image) mesher->SetInputData(1, image);
  mesher->SetSkeletonJSON(skeletonJson_.c_str());
  mesher->SetBodyThreshold(settings.bodyThreshold);
  mesher->SetMeshingSpacing(settings.meshSpacing);
  mesher->SetMaxTets(static_cast<vtkIdType>(settings.maxTets));
  mesher->SetRadiusEdgeRatio(settings.radiusEdgeRatio);
  for (int label : settings.skinLabels) mesher->AddSkinLabel(label);
  mesher->SetSeparateContacts(settings.separateContacts);
  mesher->AddObserver(vtkCommand::ProgressEvent, this, &Pipeline::forwardProgressText);
  auto mesherErrors = captureErrors(mesher);
  mesher->Update();
  vtkUnstructuredGrid* mesh = mesher->GetOutput();
  requireOutput(mesh && mesh->GetNumberOfCells() > 0, "meshing " + labelsName, mesherErrors);
  timed("mesh", secondsSince(t0));
  report_.push_back("tet mesh: " + std::to_string(mesh->GetNumberOfPoints()) + " nodes, " +
                    std::to_string(mesh->GetNumberOfCells()) + " tets");
  {
    std::istringstream lines(mesher->GetReport());
    for (std::string line; std::getline(lines, line);)
      if (line.rfind("body mask", 0) == 0 || line.rfind("meshing grid", 0) == 0 || line.rfind("contact ", 0) == 0 ||
          line.rfind("over the budget", 0) == 0 || line.rfind("tetgen", 0) == 0 || line.rfind("decimated", 0) == 0)
        report_.push_back(line);
  }

  note("computing bone weights (Laplace, one factorization)");
  t0 = Clock::now();
  auto weights = vtkSmartPointer<vtkReposeBoneWeights>::New();
  weights->SetInputData(mesh);
  weights->SetSkeletonJSON(skeletonJson_.c_str());
  weights->SetMaxInfluences(settings.maxInfluences);
  auto weightErrors = captureErrors(weights);
  weights->Update();
  vtkUnstructuredGrid* weighted = weights->GetOutput();
  requireOutput(weighted && weighted->GetPointData()->GetArray(repose::arrays::kWeights), "bone weights", weightErrors);
  timed("weights", secondsSince(t0));
  {
    std::ostringstream m;
    m << "weights: min raw " << weights->GetMinimumRawWeight() << ", max raw " << weights->GetMaximumRawWeight()
      << ", max |sum-1| " << weights->GetMaximumSumError();
    report_.push_back(m.str());
  }
  restMesh_ = vtkSmartPointer<vtkUnstructuredGrid>::New();
  restMesh_->ShallowCopy(weighted);

  note("extracting skin and bone surfaces");
  t0 = Clock::now();
  auto extractor = vtkSmartPointer<vtkReposeSurfaceExtractor>::New();
  extractor->SetInputData(0, labels);
  if (image) extractor->SetInputData(1, image);
  extractor->SetSkeletonJSON(skeletonJson_.c_str());
  extractor->SetBodyThreshold(settings.bodyThreshold);
  extractor->SetTargetReduction(settings.surfaceReduction);
  auto extractorErrors = captureErrors(extractor);
  extractor->Update();
  requireOutput(extractor->GetOutput()->GetNumberOfPoints() > 0, "surface extraction", extractorErrors);
  timed("surfaces", secondsSince(t0));

  note("binding surfaces to the tet mesh");
  t0 = Clock::now();
  auto binding = vtkSmartPointer<vtkReposeSurfaceBinding>::New();
  binding->SetInputConnection(0, extractor->GetOutputPort());
  binding->SetInputData(1, restMesh_);
  auto bindingErrors = captureErrors(binding);
  binding->Update();
  requireOutput(binding->GetOutput()->GetPointData()->GetArray(repose::arrays::kBoundTet) != nullptr, "surface binding",
                bindingErrors);
  restSurfaces_ = vtkSmartPointer<vtkPolyData>::New();
  restSurfaces_->ShallowCopy(binding->GetOutput());
  timed("binding", secondsSince(t0));
  report_.push_back("surfaces: " + std::to_string(restSurfaces_->GetNumberOfPoints()) + " vertices, " +
                    std::to_string(restSurfaces_->GetNumberOfCells()) + " triangles, " +
                    std::to_string(binding->GetOutsideCount()) + " vertices outside the tet mesh");
  if (cancel_ && cancel_()) throw Cancelled();
  connectPosing();
}

std::string Pipeline::genericCaseTable() const {
  std::vector<int> values, bones;
  vtkDataArray* scalars = restLabels_->GetPointData()->GetScalars();
  std::set<int> seen;
  for (vtkIdType i = 0, n = scalars->GetNumberOfTuples(); i < n; ++i) seen.insert(int(scalars->GetTuple1(i)));
  values.assign(seen.begin(), seen.end());
  for (const Joint& j : parseSkeletonJson(skeletonJson_).joints) bones.insert(bones.end(), j.labels.begin(), j.labels.end());
  return labelTableToTsv(genericLabelTable(values, bones));
}

std::vector<std::string> Pipeline::caseFileNames(const std::string& labelsExtension) {
  return {"mesh.vtu", "surfaces.vtp", "skeleton.json", "labels" + labelsExtension, "labels.tsv", "manifest.json"};
}

void Pipeline::saveCase(const std::string& caseDir, const std::string& labelsExtension) const {
  if (!restMesh_) throw std::runtime_error("nothing to save: the case is not prepared");
  AtomicOutputs out(caseDir);
  writeMesh(restMesh_, out.stage("mesh.vtu"));
  writeSurfaces(restSurfaces_, out.stage("surfaces.vtp"));
  writeTextFile(out.stage("skeleton.json"), skeletonJson_);
  writeLabelImage(restLabels_, out.stage("labels" + labelsExtension));
  writeTextFile(out.stage("labels.tsv"), labelTableTsv_.empty() ? genericCaseTable() : labelTableTsv_);

  Json::Value manifest;
  manifest["format"] = "repose-case";
  manifest["version"] = kCaseVersion;
  manifest["mesh"] = "mesh.vtu";
  manifest["surfaces"] = "surfaces.vtp";
  manifest["skeleton"] = "skeleton.json";
  manifest["labels"] = "labels" + labelsExtension;
  manifest["labelTable"] = "labels.tsv";
  manifest["nodes"] = Json::Int64(restMesh_->GetNumberOfPoints());
  manifest["tets"] = Json::Int64(restMesh_->GetNumberOfCells());
  for (const auto& line : report_) manifest["report"].append(line);
  for (const auto& t : timings_) manifest["seconds"][t.stage] = t.seconds;
  Json::StreamWriterBuilder builder;
  builder["indentation"] = "  ";
  writeTextFile(out.stage("manifest.json"), Json::writeString(builder, manifest) + "\n");
  out.commit();
}

void Pipeline::loadCase(const std::string& caseDir) {
  const std::string manifestPath = caseDir + "/manifest.json";
  if (!fileExists(caseDir)) throw std::runtime_error(caseDir + ": no such case directory");
  if (!fileExists(manifestPath))
    throw std::runtime_error(caseDir + ": not a prepared case (no manifest.json; run 'repose prepare')");
  Json::Value manifest;
  {
    try {
      manifest = parseJsonText(readTextFile(manifestPath), false);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(manifestPath + ": " + e.what());
    }
    if (!manifest.isObject() || !manifest["format"].isString() || manifest["format"].asString() != "repose-case")
      throw std::runtime_error(manifestPath + ": not a Repose case manifest");
  }
  if (!manifest["version"].isInt() || manifest["version"].asInt() != kCaseVersion)
    throw std::runtime_error(manifestPath + ": case version " + brief(manifest["version"]) +
                             " is not " + std::to_string(kCaseVersion) + " (prepare the case again)");
  const std::string meshPath = caseFile(caseDir, manifest, "mesh", manifestPath);
  const std::string surfacesPath = caseFile(caseDir, manifest, "surfaces", manifestPath);
  const std::string skeletonPath = caseFile(caseDir, manifest, "skeleton", manifestPath);
  const std::string labelsPath = caseFile(caseDir, manifest, "labels", manifestPath);
  for (const auto& p : {meshPath, surfacesPath, skeletonPath, labelsPath})
    if (!fileExists(p)) throw std::runtime_error(p + ": missing from the case directory");

  auto t0 = Clock::now();
  Skeleton skeleton;
  try {
    skeleton = parseSkeletonJson(readTextFile(skeletonPath));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(skeletonPath + ": " + e.what());
  }
  skeletonJson_ = skeletonToJson(skeleton);
  vtkSmartPointer<vtkUnstructuredGrid> mesh = readCaseMesh(meshPath, manifest, manifestPath, skeleton);
  restMesh_ = mesh;
  restSurfaces_ = readCaseSurfaces(surfacesPath, mesh->GetNumberOfCells());
  restLabels_ = readLabelVolume(labelsPath);
  checkMeshOnGrid(mesh, meshPath, restLabels_, labelsPath);
  labelsExtension_ = imageExtension(labelsPath);
  labelTableTsv_.clear();
  if (manifest.isMember("labelTable")) {  // cases saved before it was kept have none
    const std::string tablePath = caseFile(caseDir, manifest, "labelTable", manifestPath);
    if (!fileExists(tablePath)) throw std::runtime_error(tablePath + ": missing from the case directory");
    labelTableTsv_ = readTextFile(tablePath);
    try {
      parseLabelTable(labelTableTsv_, tablePath);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(e.what());
    }
  }
  timed("load case", secondsSince(t0));
  connectPosing();
}

void Pipeline::connectPosing() {
  skinning_ = vtkSmartPointer<vtkReposeSkinning>::New();
  skinning_->SetInputData(restMesh_);
  skinning_->SetSkeletonJSON(skeletonJson_.c_str());
  skinning_->SetPoseJSON("{\"rotations\": {}}");

  deformer_ = vtkSmartPointer<vtkReposeSurfaceDeformer>::New();
  deformer_->SetInputData(0, restSurfaces_);
  deformer_->SetInputConnection(1, skinning_->GetOutputPort());

  labelResampler_ = vtkSmartPointer<vtkReposePosedVolume>::New();
  labelResampler_->SetInputData(0, restLabels_);
  labelResampler_->SetInputData(1, restMesh_);
  labelResampler_->SetInputConnection(2, skinning_->GetOutputPort());
  labelResampler_->SetInterpolationToNearest();
  labelResampler_->SetBackgroundValue(0);
  if (maxPosedVoxels_ >= 0) labelResampler_->SetMaxVoxels(maxPosedVoxels_);
  imageResampler_ = displacementResampler_ = nullptr;
  relax_ = relaxBySkinning_[0] = relaxBySkinning_[1] = nullptr;
}

void Pipeline::setPose(const std::string& poseJson, const std::string& poseName) {
  if (!skinning_) throw std::runtime_error("no case loaded");
  try {
    const Pose pose = parsePoseJson(poseJson);
    validatePose(pose, parseSkeletonJson(skeletonJson_));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(poseName + ": " + e.what());
  }
  skinning_->SetPoseJSON(poseJson.c_str());
}

void Pipeline::setPose(const Pose& pose) {
  if (!skinning_) throw std::runtime_error("no case loaded");
  skinning_->SetPose(pose);
}

std::vector<Eigen::Isometry3d> Pipeline::boneTransforms() const {
  std::vector<Eigen::Isometry3d> bones;
  if (!skinning_) return bones;
  bones.resize(std::size_t(skinning_->GetNumberOfBoneTransforms()));
  for (std::size_t j = 0; j < bones.size(); ++j) {
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> m;
    skinning_->GetBoneTransform(int(j), m.data());
    bones[j].matrix() = m;
  }
  return bones;
}

namespace {
double signedVolume(vtkPoints* points, const Tets& tets) { return meshVolume(repose_vtk::ToPoints(points), tets); }
}  // namespace

double Pipeline::restMeshVolume() {
  if (!restMesh_) throw std::runtime_error("no case loaded");
  if (tets_.rows() != restMesh_->GetNumberOfCells()) tets_ = repose_vtk::ToTets(restMesh_, "the case's mesh");
  return signedVolume(restMesh_->GetPoints(), tets_);
}

PosedLabelStats Pipeline::posedLabelStats() const {
  PosedLabelStats stats;
  vtkImageData* labels = labelResampler_ ? labelResampler_->GetOutput() : nullptr;
  if (!labels || labels->GetNumberOfPoints() == 0) return stats;
  const double* spacing = labels->GetSpacing();
  stats.contestedBoneVoxels = std::size_t(labelResampler_->GetContestedBoneVoxels());
  stats.voxelMm3 = spacing[0] * spacing[1] * spacing[2];
  return stats;
}

DeformationStats Pipeline::posedStats() {
  restMeshVolume();  // caches the connectivity
  if (tetLabels_.size() != std::size_t(tets_.rows())) {
    tetLabels_.assign(std::size_t(tets_.rows()), 0);
    if (vtkDataArray* labels = restMesh_->GetCellData()->GetArray(repose::arrays::kLabel))
      for (vtkIdType c = 0; c < labels->GetNumberOfTuples() && c < tets_.rows(); ++c)
        tetLabels_[std::size_t(c)] = static_cast<std::int32_t>(labels->GetTuple1(c));
  }
  return deformationStats(repose_vtk::ToPoints(restMesh_->GetPoints()), repose_vtk::ToPoints(posedMesh()->GetPoints()), tets_, tetLabels_);
}

double Pipeline::posedMeshVolume() {
  restMeshVolume();  // makes sure the connectivity is cached
  return signedVolume(posedMesh()->GetPoints(), tets_);
}

double Pipeline::lastSkinningSeconds() const { return skinning_ ? skinning_->GetLastSkinningTime() : 0.0; }

void Pipeline::setSkinningMethod(const std::string& method) {
  if (!skinning_) throw std::runtime_error("no case loaded");
  if (method == "dqs")
    skinning_->SetSkinningMethodToDualQuaternion();
  else if (method == "lbs")
    skinning_->SetSkinningMethodToLinearBlend();
  else
    throw std::runtime_error("unknown skinning method '" + method + "' (use dqs or lbs)");
  if (relax_) setRelaxation(true, relax_->GetPoissonRatio(), relax_->GetOuterIterations());  // that method's filter
}

void Pipeline::setRestImage(vtkImageData* image, const std::string& imageName) {
  if (!restLabels_) throw std::runtime_error("no case loaded");
  checkSameGrid(restLabels_, "the case's label volume", image, imageName);
  restImage_ = image;
  imageResampler_ = vtkSmartPointer<vtkReposePosedVolume>::New();
  imageResampler_->SetInputData(0, restImage_);
  imageResampler_->SetInputData(1, restMesh_);
  imageResampler_->SetInputConnection(2, posedSource()->GetOutputPort());
  imageResampler_->SetInterpolationToLinear();
  // Air outside the body.
  double range[2];
  image->GetPointData()->GetScalars()->GetRange(range);
  imageResampler_->SetBackgroundValue(range[0]);
  if (maxPosedVoxels_ >= 0) imageResampler_->SetMaxVoxels(maxPosedVoxels_);
}

void Pipeline::setMaxPosedVoxels(double voxels) {
  maxPosedVoxels_ = voxels;
  for (vtkReposePosedVolume* resampler : {labelResampler_.Get(), imageResampler_.Get(), displacementResampler_.Get()})
    if (resampler) resampler->SetMaxVoxels(voxels);
}

/// Runs a posing filter and records its time, only when it actually executed (the pipeline
/// skips filters whose inputs did not change).
void Pipeline::runStage(vtkAlgorithm* filter, const std::string& stage) {
  const vtkMTimeType before = filter->GetOutputDataObject(0) ? filter->GetOutputDataObject(0)->GetMTime() : 0;
  auto t0 = Clock::now();
  updateOrThrow(filter, stage);
  if (filter->GetOutputDataObject(0)->GetMTime() != before) timed(stage, secondsSince(t0));
}

vtkAlgorithm* Pipeline::posedSource() const {
  if (relax_) return relax_;
  return skinning_;
}

void Pipeline::setRelaxation(bool enabled, double poisson, int outerIterations) {
  if (!skinning_) throw std::runtime_error("no case loaded");
  if (!(poisson > -1 && poisson < 0.5)) throw std::runtime_error("Poisson's ratio must be in (-1, 0.5)");
  if (outerIterations < 1) throw std::runtime_error("relaxation needs at least one iteration");
  if (enabled) {
    vtkSmartPointer<vtkReposeCorotationalRelax>& filter = relaxBySkinning_[skinning_->GetSkinningMethod() != 0];
    if (!filter) {
      filter = vtkSmartPointer<vtkReposeCorotationalRelax>::New();
      filter->SetInputConnection(0, skinning_->GetOutputPort());
      filter->SetInputData(1, restMesh_);
      filter->SetSkeletonJSON(skeletonJson_.c_str());
      filter->AddObserver(vtkCommand::ProgressEvent, this, &Pipeline::forwardProgressText);  // where the FEM is
      relaxStrainedRegionThreshold_ = filter->GetStrainedRegionThreshold();
    }
    relax_ = filter;
    relax_->ResetCancel();  // a cancel meant for an earlier run that had already ended
    relax_->SetWarmStart(relaxWarmStart_);
    relax_->SetPoissonRatio(poisson);
    relax_->SetOuterIterations(outerIterations);
    relax_->SetModel(relaxModel_);
    relax_->SetVolumeRegions(relaxVolume_);
    relax_->SetContinuation(relaxContinuation_);
    relax_->SetStrainedRegionThreshold(relaxStrainedRegionFirst_ ? relaxStrainedRegionThreshold_ : 0.0);
  } else {
    relax_ = nullptr;
  }
  vtkAlgorithmOutput* port = posedSource()->GetOutputPort();
  deformer_->SetInputConnection(1, port);
  labelResampler_->SetInputConnection(2, port);
  if (imageResampler_) imageResampler_->SetInputConnection(2, port);
  if (displacementResampler_) displacementResampler_->SetInputConnection(2, port);
}

void Pipeline::setRelaxationModel(vtkReposeCorotationalRelax::ModelType model) {
  relaxModel_ = model;
  if (relax_) relax_->SetModel(relaxModel_);
}

void Pipeline::setRelaxationVolume(vtkReposeCorotationalRelax::VolumeRegionsType regions) {
  relaxVolume_ = regions;
  if (relax_) relax_->SetVolumeRegions(relaxVolume_);
}

void Pipeline::setRelaxationContinuation(vtkReposeCorotationalRelax::ContinuationType mode) {
  relaxContinuation_ = mode;
  if (relax_) relax_->SetContinuation(relaxContinuation_);
}

void Pipeline::setRelaxationStrainedRegion(bool first) {
  relaxStrainedRegionFirst_ = first;
  if (relax_) relax_->SetStrainedRegionThreshold(relaxStrainedRegionFirst_ ? relaxStrainedRegionThreshold_ : 0.0);
}

void Pipeline::setRelaxationWarmStart(bool enabled) {
  relaxWarmStart_ = enabled;
  for (auto& filter : relaxBySkinning_)
    if (filter) filter->SetWarmStart(enabled);
}

vtkReposeCorotationalRelax* Pipeline::relaxation() const { return relax_; }

void Pipeline::cancelRelaxation() {
  if (relax_) relax_->Cancel();
}

std::string Pipeline::relaxationSummary() const {
  if (!relax_) return "";
  std::ostringstream m, pinched;
  if (relax_->GetPinchedNodes() > 0)
    pinched << ", " << relax_->GetPinchedNodes() << " nodes pinched between bones (up to "
            << std::setprecision(2) << relax_->GetPinchedShortfall() << " mm short of room: no solve can unfold them)";
  m << "FEM relaxation: ";
  if (relax_->GetModel() == vtkReposeCorotationalRelax::MODEL_FIXED_COROTATED)
    m << relax_->GetNewtonIterations() << " Newton iterations, ";
  m << relax_->GetCGIterations() << " CG iterations, relative residual "
    << relax_->GetRelativeResidual() << ", inverted tets " << relax_->GetInvertedBefore() << " -> "
    << relax_->GetInvertedAfter()
    << (relax_->GetInvertedRigidAfter() > 0
          ? " (" + std::to_string(relax_->GetInvertedRigidAfter()) + " with only bone nodes)"
          : std::string())
    << pinched.str()
    << (relax_->GetUntangledNodes() > 0
          ? ", " + std::to_string(relax_->GetUntangledNodes()) + " nodes untangled (their neighbourhoods " +
              std::to_string(relax_->GetUntangleNewtonIterations()) + " Newton iterations)"
          : std::string())
    << (relax_->GetStrainedRegionNodes() > 0
          ? ", strained region first (" + std::to_string(relax_->GetStrainedRegionNodes()) + " nodes, " +
              std::to_string(relax_->GetStrainedRegionNewtonIterations()) + " Newton iterations)"
          : std::string())
    << (relax_->GetWarmStarted() ? ", started from the last relaxation" : "")
    << (relax_->GetContinuationSteps() > 0
          ? std::string(", fold-free continuation ") + std::to_string(relax_->GetContinuationSteps()) + " steps " +
              (relax_->GetContinuationUsed() ? "(kept)"
                                             : "(not kept: it met a fold no pose on its way avoids; "
                                               "--relax-continuation never saves its time)")
          : std::string())
    << ", " << relax_->GetLastRelaxTime() << " s (assembly " << relax_->GetLastAssemblyTime() << " s, solves "
    << relax_->GetLastSolveTime() << " s, strained region " << relax_->GetLastStrainedRegionTime()
    << " s, untangling " << relax_->GetLastUntangleTime() << " s, continuation "
    << relax_->GetLastContinuationTime() << " s)";
  return m.str();
}

vtkUnstructuredGrid* Pipeline::posedMesh() {
  runStage(skinning_, "skinning");
  if (relax_) {
    try {
      runStage(relax_, "FEM relaxation");
    } catch (const std::runtime_error&) {
      if (relax_->GetCancelled()) throw Cancelled("relaxation cancelled");
      throw;
    }
    return relax_->GetOutput();
  }
  return skinning_->GetOutput();
}

vtkPolyData* Pipeline::posedSurfaces() {
  posedMesh();
  runStage(deformer_, "posed surfaces");
  return deformer_->GetOutput();
}

vtkImageData* Pipeline::posedLabels() {
  posedMesh();
  runStage(labelResampler_, "posed labels");
  return labelResampler_->GetOutput();
}

vtkImageData* Pipeline::posedImage() {
  if (!imageResampler_) return nullptr;
  posedMesh();
  runStage(imageResampler_, "posed image");
  return imageResampler_->GetOutput();
}

vtkImageData* Pipeline::posedDisplacement() {
  if (!skinning_) throw std::runtime_error("no case loaded");
  if (!displacementResampler_) {
    // The rest labels give the grid (the CT's, when there is one: checked to be the same).
    displacementResampler_ = vtkSmartPointer<vtkReposePosedVolume>::New();
    displacementResampler_->SetInputData(0, restLabels_);
    displacementResampler_->SetInputData(1, restMesh_);
    displacementResampler_->SetInputConnection(2, posedSource()->GetOutputPort());
    displacementResampler_->OutputDisplacementOn();
    if (maxPosedVoxels_ >= 0) displacementResampler_->SetMaxVoxels(maxPosedVoxels_);
  }
  posedMesh();
  runStage(displacementResampler_, "displacement");
  return displacementResampler_->GetOutput();
}

}  // namespace repose
