#pragma once
// The Repose pipeline as one object, shared by the CLI and the GUI (no Qt here, so it is testable
// headless). Preprocessing (mesh, weights, surfaces, binding) runs once and is saved as a case
// directory; posing re-runs only skinning, surface deformation and resampling.
#include <functional>
#include <stdexcept>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vtkImageData.h>  // complete for the inline accessors below
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "filter_errors.h"
#include "scan_files.h"
#include "vtkReposeCorotationalRelax.h"  // its enums name the relaxation settings

class vtkAlgorithm;
class vtkObject;
class vtkReposeBodyMesher;
class vtkReposeBoneWeights;
class vtkReposeSurfaceExtractor;
class vtkReposeSurfaceBinding;
class vtkReposeSkinning;
class vtkReposeSurfaceDeformer;
class vtkReposePosedVolume;

namespace repose {

struct Pose;
struct DeformationStats;
struct PosedLabelStats;

struct PrepareSettings {
  double bodyThreshold = -500.0;   ///< HU, with a CT image
  double meshSpacing = 0.0;        ///< mm; 0 = chosen from maxTets (the label spacing if it fits)
  double maxTets = 3.0e6;          ///< tet budget when meshSpacing is 0 (0 = none: the label spacing)
  double radiusEdgeRatio = 2.0;    ///< TetGen quality bound
  int maxInfluences = 4;           ///< bone weights kept per node
  double surfaceReduction = 0.0;   ///< fraction of surface triangles removed by decimation
  std::vector<int> skinLabels;     ///< removed before meshing (see vtkReposeBodyMesher::AddSkinLabel)
  bool separateContacts = true;    ///< part body parts that touch in the scan
};

struct StageTime {
  std::string stage;
  double seconds;
};

/// Thrown by Pipeline::prepare when the cancel check returns true (between stages).
struct Cancelled : std::runtime_error {
  explicit Cancelled(const char* what = "preprocessing cancelled") : std::runtime_error(what) {}
};

class Pipeline {
public:
  Pipeline();
  ~Pipeline();

  using Progress = std::function<void(const std::string& stage)>;
  void setProgress(Progress progress) { progress_ = std::move(progress); }
  /// Polled between preprocessing stages (e.g. from another thread's cancel button); returning
  /// true makes prepare() throw Cancelled. A running stage (TetGen) is not interrupted.
  void setCancelCheck(std::function<bool()> cancel) { cancel_ = std::move(cancel); }

  // --- preprocessing -------------------------------------------------------------------------
  /// Validates the skeleton against the labels (every bone label present) and runs meshing,
  /// weights, surface extraction and binding. `image` may be null. Names are used in messages.
  void prepare(vtkImageData* labels, const std::string& labelsName, const std::string& skeletonJson,
               const std::string& skeletonName, vtkImageData* image, const std::string& imageName,
               const PrepareSettings& settings);
  /// Writes mesh.vtu, surfaces.vtp, skeleton.json, labels<ext>, labels.tsv and manifest.json
  /// atomically. labels.tsv (listed in the manifest as "labelTable") is the label table set with
  /// setLabelTableTsv(), or else one naming every label value label_<value> (bone when the skeleton
  /// uses it): value<TAB>name<TAB>kind lines with a header, plus r g b a columns when colours are known.
  void saveCase(const std::string& caseDir, const std::string& labelsExtension = ".nii.gz") const;
  /// The files saveCase writes into the case folder.
  static std::vector<std::string> caseFileNames(const std::string& labelsExtension);
  /// Throws std::runtime_error naming the missing or broken file. Cases saved before the label
  /// table was kept load too (labelTableTsv() is then empty).
  void loadCase(const std::string& caseDir);
  /// The label table of the case (labels.tsv text, see saveCase), kept with it.
  void setLabelTableTsv(const std::string& tsv) { labelTableTsv_ = tsv; }
  const std::string& labelTableTsv() const { return labelTableTsv_; }

  // --- posing --------------------------------------------------------------------------------
  /// Validates (unknown joints, NaN, zero axis) and sets the pose; throws std::runtime_error.
  void setPose(const std::string& poseJson, const std::string& poseName);
  /// Sets an already validated pose (e.g. retargeted from motion capture, or the GUI's sliders):
  /// typed all the way to the skinning, posed to the same bits as its JSON.
  void setPose(const Pose& pose);
  /// The bone transforms (rest -> posed, one per joint) the last posed mesh was skinned with: for
  /// drawing the skeleton without a second pass of forward kinematics. Empty before posedMesh().
  std::vector<Eigen::Isometry3d> boneTransforms() const;
  void setSkinningMethod(const std::string& method);  ///< "dqs" | "lbs"
  /// Corotational FEM relaxation of the skinned mesh (bone nodes stay rigid); everything posed
  /// downstream (surfaces, volumes) then follows the relaxed mesh.
  void setRelaxation(bool enabled, double poisson = 0.49, int outerIterations = 1);
  /// Fixed-corotated (default: nonlinear, keeps volume, untangles inverted tets) or linear (one
  /// linearised corotational solve per outer iteration: faster, volume kept to first order).
  void setRelaxationModel(vtkReposeCorotationalRelax::ModelType model);
  /// Regions whose volume the fixed-corotated relaxation holds as a whole: segments (default, one
  /// per bone's segment of the body), tissues (each label within each segment), body or none
  /// (see vtkReposeCorotationalRelax::VolumeRegions).
  void setRelaxationVolume(vtkReposeCorotationalRelax::VolumeRegionsType regions);
  /// When the fixed-corotated solve leaves tets inverted: if-inverted (default) solves again by the
  /// fold-free continuation from the rest shape, never keeps the direct result, always uses the
  /// continuation in every pose (see vtkReposeCorotationalRelax::Continuation).
  void setRelaxationContinuation(vtkReposeCorotationalRelax::ContinuationType mode);
  /// From a skinned start, relax the strained region (the joints) on its own before the whole mesh
  /// (default), or the whole mesh from the start (see vtkReposeCorotationalRelax::StrainedRegionThreshold).
  void setRelaxationStrainedRegion(bool first);
  /// Each relaxation starts from the last one's correction (for a sequence of poses; see
  /// vtkReposeCorotationalRelax::WarmStart). Kept per skinning method, so --compare's lbs+fem and
  /// dqs+fem each follow their own history.
  void setRelaxationWarmStart(bool enabled);
  /// One line on the last relaxation: CG iterations, residual, inverted tets before and after.
  std::string relaxationSummary() const;
  /// Stops a running relaxation (from any thread) at its next check, a few seconds at most: the
  /// call that runs it (posedMesh() and what follows it) throws Cancelled. No-op without relaxation.
  void cancelRelaxation();
  /// The relaxation filter (its figures of the last run), or null when relaxation is off.
  vtkReposeCorotationalRelax* relaxation() const;
  /// Optional intensity image on the rest label grid, posed with trilinear sampling.
  void setRestImage(vtkImageData* image, const std::string& imageName);

  vtkUnstructuredGrid* posedMesh();
  vtkPolyData* posedSurfaces();
  vtkImageData* posedLabels();
  vtkImageData* posedImage();   ///< null without a rest image
  /// The map the posed image is pulled through, on the posed grid: 3 floats per voxel "Displacement",
  /// mm along the LPS axes from each voxel centre to its rest point (0 outside the body).
  vtkImageData* posedDisplacement();
  /// Largest posed volume in voxels: a larger one makes posedLabels()/posedImage() throw with its size
  /// and the posed body's span (default: vtkReposePosedVolume's, 512 M; 0 = no limit).
  void setMaxPosedVoxels(double voxels);

  /// Signed volume of the rest and of the posed tet mesh (mm^3).
  double restMeshVolume();
  double posedMeshVolume();
  /// Volume fidelity of the current posed mesh against the rest mesh (per tet label too).
  DeformationStats posedStats();
  /// Figures of the last posed label volume made (zero before posedLabels()).
  PosedLabelStats posedLabelStats() const;
  /// Seconds of the last skinning run alone (the interactive cost).
  double lastSkinningSeconds() const;

  vtkUnstructuredGrid* restMesh() const { return restMesh_; }
  vtkPolyData* restSurfaces() const { return restSurfaces_; }
  vtkImageData* restLabels() const { return restLabels_; }
  vtkImageData* restImage() const { return restImage_; }  ///< null without a rest image
  const std::string& skeletonJson() const { return skeletonJson_; }
  const std::string& labelsExtension() const { return labelsExtension_; }

  /// Time of every stage run so far, in order.
  const std::vector<StageTime>& timings() const { return timings_; }
  /// One line per preprocessing figure (counts, weight checks), for the manifest and the console.
  const std::vector<std::string>& reportLines() const { return report_; }

private:
  void connectPosing();
  std::string genericCaseTable() const;
  void runStage(vtkAlgorithm* filter, const std::string& stage);
  void note(const std::string& stage);
  void timed(const std::string& stage, double seconds);

  /// A filter's progress text (e.g. the mesher's before TetGen) passed on to the progress callback.
  void forwardProgressText(vtkObject* caller, unsigned long event, void* data);
  Progress progress_;
  std::function<bool()> cancel_;
  std::string skeletonJson_, labelsExtension_ = ".nii.gz", labelTableTsv_;
  vtkSmartPointer<vtkImageData> restLabels_, restImage_;
  vtkSmartPointer<vtkUnstructuredGrid> restMesh_;
  vtkSmartPointer<vtkPolyData> restSurfaces_;
  vtkSmartPointer<vtkReposeSkinning> skinning_;
  vtkSmartPointer<vtkReposeCorotationalRelax> relax_;  // null when relaxation is off
  vtkSmartPointer<vtkReposeCorotationalRelax> relaxBySkinning_[2];  // per vtkReposeSkinning::SkinningMethod
  bool relaxWarmStart_ = false;
  int relaxModel_ = vtkReposeCorotationalRelax::MODEL_FIXED_COROTATED;
  int relaxVolume_ = vtkReposeCorotationalRelax::VOLUME_SEGMENTS;
  int relaxContinuation_ = vtkReposeCorotationalRelax::CONTINUATION_IF_INVERTED;
  bool relaxStrainedRegionFirst_ = true;
  double relaxStrainedRegionThreshold_ = 0.0;            // the filter's default, read when it is made
  vtkAlgorithm* posedSource() const;
  vtkSmartPointer<vtkReposeSurfaceDeformer> deformer_;
  vtkSmartPointer<vtkReposePosedVolume> labelResampler_, imageResampler_, displacementResampler_;
  double maxPosedVoxels_ = -1;  // < 0: the resamplers' default
  std::vector<StageTime> timings_;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> tets_;  // rest mesh connectivity, for volumes
  std::vector<std::int32_t> tetLabels_;
  std::vector<std::string> report_;
};

}  // namespace repose
