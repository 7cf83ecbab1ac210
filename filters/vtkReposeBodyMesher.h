#ifndef vtkReposeBodyMesher_h
#define vtkReposeBodyMesher_h
// Volumetrization (stage 1): label volume (+ CT) -> tetrahedral mesh of the body with bone nodes tagged.
//
// Input port 0: label image (integer scalars; origin, spacing and direction honoured).
// Input port 1 (optional): intensity image (CT) on the same grid.
// Output: vtkUnstructuredGrid of VTK_TETRA cells in physical coordinates (mm), positively oriented,
// point data "FixedBone" (int: joint index of the bone the node lies in, -1 = free) and cell data
// "Label" (int: label value at the tet's centroid).
//
// The stages and their heuristics are repose::meshBody (core/body_meshing.h): body mask on a meshing
// grid chosen for MaxTets -> surface (this module's vtkReposeSurfaceExtractor::ContourMask: discrete
// flying edges, windowed-sinc smoothing, decimation) -> TetGen with seed points in every bone -> node
// and tet tagging -> only mesh components containing bone nodes kept. RequestData converts the
// images, calls it and converts the mesh back.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>
#include <vector>

class vtkAlgorithmOutput;
class vtkImageData;

class REPOSEFILTERS_EXPORT vtkReposeBodyMesher : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkReposeBodyMesher* New();
  vtkTypeMacro(vtkReposeBodyMesher, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// skeleton.json text; the bones are the labels listed by its joints (required).
  vtkSetStdStringFromCharMacro(SkeletonJSON);
  vtkGetCharFromStdStringMacro(SkeletonJSON);

  /// HU above which CT voxels belong to the body (used only with an intensity input). Default -500.
  vtkSetMacro(BodyThreshold, double);
  vtkGetMacro(BodyThreshold, double);

  /// Remove the outer voxel layer of the body mask before meshing (default on). Ignored when skin
  /// labels are given: the skin is removed instead.
  vtkSetMacro(PeelOuterLayer, bool);
  vtkGetMacro(PeelOuterLayer, bool);
  vtkBooleanMacro(PeelOuterLayer, bool);

  /// Labels of the skin: removed before meshing (as the paper does), so skins touching in the scan
  /// part. None by default.
  void AddSkinLabel(int label) { this->SkinLabels.push_back(label), this->Modified(); }
  void RemoveAllSkinLabels() { this->SkinLabels.clear(), this->Modified(); }
  int GetNumberOfSkinLabels() { return static_cast<int>(this->SkinLabels.size()); }

  /// Cut apart the parts that touch in the scan (an arm against the torso, a hand against a thigh,
  /// the thighs) where their skins meet in a crease, so posing them apart leaves no tissue web
  /// (default on; see separateContacts in contact_separation.h).
  vtkSetMacro(SeparateContacts, bool);
  vtkGetMacro(SeparateContacts, bool);
  vtkBooleanMacro(SeparateContacts, bool);

  /// Spacing (mm) of the lattice the surface is extracted on; 0 (default) = chosen from MaxTets, or
  /// the image spacing without a budget. Coarser values give fewer tets.
  vtkSetClampMacro(MeshingSpacing, double, 0.0, 1000.0);
  vtkGetMacro(MeshingSpacing, double);

  /// Tet budget (0 = none, the default): with MeshingSpacing 0, the finest meshing spacing whose
  /// predicted tet count fits it is used (see chooseMeshSpacing in mesh_budget.h), and the mesh is
  /// made once more, coarser, if TetGen exceeds it by a fifth.
  vtkSetClampMacro(MaxTets, vtkIdType, 0, VTK_ID_MAX);
  vtkGetMacro(MaxTets, vtkIdType);
  /// The meshing spacing of the last run (mm).
  vtkGetMacro(MeshingSpacingUsed, double);

  /// TetGen quality bound (radius-edge ratio, > 1; default 2.0, TetGen's own; 1.6 gives ~35 % more tets at ~4x the time) and maximum tet volume (mm^3, 0 = none).
  vtkSetClampMacro(RadiusEdgeRatio, double, 1.05, 100.0);
  vtkGetMacro(RadiusEdgeRatio, double);
  vtkSetClampMacro(MaxTetVolume, double, 0.0, 1e12);
  vtkGetMacro(MaxTetVolume, double);

  /// Windowed-sinc smoothing iterations of the body surface (0 = none; default 10).
  /// Fraction of the body surface's triangles removed by quadric decimation before meshing (the
  /// marching-cubes surface has several triangles per voxel face; the surface density sets the tet
  /// count). If TetGen finds the decimated surface self-intersecting, meshing is redone without it.
  vtkSetClampMacro(SurfaceReduction, double, 0.0, 0.95);
  vtkGetMacro(SurfaceReduction, double);
  vtkSetClampMacro(SurfaceSmoothingIterations, int, 0, 1000);
  vtkGetMacro(SurfaceSmoothingIterations, int);

  /// Spacing, in voxels, of the bone seed points on bone boundaries and in bone interiors
  /// (0 = automatic: 2 and 4 voxels, scaled up when MeshingSpacing is coarser than the image).
  vtkSetClampMacro(SeedSurfaceStep, int, 0, 1000);
  vtkGetMacro(SeedSurfaceStep, int);
  vtkSetClampMacro(SeedInteriorStep, int, 0, 1000);
  vtkGetMacro(SeedInteriorStep, int);

  /// Optional intensity image (CT) on the label grid.
  void SetIntensityConnection(vtkAlgorithmOutput* port) { this->SetInputConnection(1, port); }
  void SetIntensityData(vtkImageData* image);

  /// Figures of the last run.
  vtkGetMacro(NumberOfNodes, vtkIdType);
  vtkGetMacro(NumberOfTets, vtkIdType);
  vtkGetMacro(NumberOfSurfaceTriangles, vtkIdType);
  vtkGetMacro(NumberOfSeedPoints, vtkIdType);
  vtkGetMacro(NumberOfFixedNodes, vtkIdType);
  /// Bone nodes made free because a tet edge joined them to another bone's node (across a joint).
  vtkGetMacro(NumberOfFreedContactNodes, vtkIdType);
  vtkGetMacro(TotalSeconds, double);
  vtkGetMacro(TetGenSeconds, double);
  /// Body voxels (of the meshing grid) removed to part touching body parts, and one line per contact.
  vtkGetMacro(NumberOfContactVoxelsCut, vtkIdType);
  const char* GetContactReport() { return this->ContactReport.c_str(); }
  /// Multi-line text report of the last run (counts and timings per stage).
  const char* GetReport() { return this->Report.c_str(); }

protected:
  vtkReposeBodyMesher();
  ~vtkReposeBodyMesher() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::string SkeletonJSON;
  double BodyThreshold = -500.0;
  bool PeelOuterLayer = true;
  bool SeparateContacts = true;
  std::vector<int> SkinLabels;
  double MeshingSpacing = 0.0;
  vtkIdType MaxTets = 0;
  double MeshingSpacingUsed = 0.0;
  double RadiusEdgeRatio = 2.0;
  double MaxTetVolume = 0.0;
  int SurfaceSmoothingIterations = 10;
  double SurfaceReduction = 0.0;
  int SeedSurfaceStep = 0;
  int SeedInteriorStep = 0;

  vtkIdType NumberOfNodes = 0;
  vtkIdType NumberOfTets = 0;
  vtkIdType NumberOfSurfaceTriangles = 0;
  vtkIdType NumberOfSeedPoints = 0;
  vtkIdType NumberOfFixedNodes = 0;
  vtkIdType NumberOfFreedContactNodes = 0;
  double TotalSeconds = 0;
  double TetGenSeconds = 0;
  vtkIdType NumberOfContactVoxelsCut = 0;
  std::string ContactReport;
  std::string Report;

private:
  struct Steps; // the core's options and figures, and the surface extraction it calls back

  vtkReposeBodyMesher(const vtkReposeBodyMesher&) = delete;
  void operator=(const vtkReposeBodyMesher&) = delete;
};

#endif
