#include "repose_pipeline.h"

#include <optional>

#include "case_files.h"
#include "mesh_io.h"
#include "json_text.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include <json/json.h>

#include <vtkAlgorithm.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkPoints.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "ReposeMeshConversion.h"
#include "vtkReposeBodyMesher.h"
#include "vtkReposeCorotationalRelax.h"
#include "vtkReposeBoneWeights.h"
#include "vtkReposePosedVolume.h"
#include "vtkReposeSkinning.h"
#include "vtkReposeSurfaceBinding.h"
#include "vtkReposeSurfaceDeformer.h"
#include "vtkReposeSurfaceExtractor.h"

#include "atomic_outputs.h"
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

}  // namespace

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
