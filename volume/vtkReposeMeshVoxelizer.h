#ifndef vtkReposeMeshVoxelizer_h
#define vtkReposeMeshVoxelizer_h
// Surface meshes -> one label volume (repose::voxelizeLabels: inside where the generalized winding
// number is at least 1/2, so holes, overlapping pieces and cavities are taken as they come).
//
// Input port 0 (repeatable): one vtkPolyData per surface (triangles; other polygons are split into
// fans), points in physical LPS millimetres. By default connection 0 is the skin (its interior becomes
// soft tissue, label 1) and the others are bones; SetPartName/SetPartRole/SetPartSource change that.
// Output: vtkImageData with int scalars "Labels": 0 background, 1 skin interior, then the bones and
// the tissues in connection order. Bones win over tissues over skin. Bones are solid: the thin
// hollows their surfaces wall in are filled (MaxMarrowRadius, HollowBones).
// The lattice is the reference image's (SetReferenceImage) when given, else axis-aligned cubic voxels
// of VoxelSize fitted to the skin's bounds plus PaddingVoxels. More than MaxVoxels voxels is an error.
// After Update(): GetLabelTableTSV() (value, name, kind: what `repose prepare --label-table` reads),
// GetReport() (one line per surface, then the warnings) and GetNumberOfWarnings().

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"
#include "vtkSmartPointer.h"

#include <map>
#include <string>

class vtkImageData;

class REPOSEVOLUME_EXPORT vtkReposeMeshVoxelizer : public vtkImageAlgorithm
{
public:
  static vtkReposeMeshVoxelizer* New();
  vtkTypeMacro(vtkReposeMeshVoxelizer, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum
  {
    Skin = 0,
    Bone = 1,
    Tissue = 2
  };

  /// Label name, role and source file (for messages) of input connection `index`. Defaults: index 0
  /// "soft_tissue" Skin, others "bone_<index>" Bone.
  void SetPartName(int index, const char* name);
  const char* GetPartName(int index);
  void SetPartRole(int index, int role);
  int GetPartRole(int index);
  void SetPartSource(int index, const char* source);
  /// Forgets every name, role and source.
  void ClearParts();

  /// Cubic voxel size (mm) of the lattice fitted to the skin (default 1).
  vtkSetClampMacro(VoxelSize, double, 1e-6, 1e6);
  vtkGetMacro(VoxelSize, double);
  /// Background voxels around the skin's bounds (default 2).
  vtkSetClampMacro(PaddingVoxels, double, 0.0, 1000.0);
  vtkGetMacro(PaddingVoxels, double);
  /// Largest voxel count accepted (default 512 Mi).
  vtkSetClampMacro(MaxVoxels, double, 1.0, 1e15);
  vtkGetMacro(MaxVoxels, double);

  /// Bones are solid: a hollow a bone's surface walls in (a cortical shell's marrow) is bone when the
  /// largest ball it holds has at most this radius in mm (default 30); wider ones (a cranial cavity)
  /// stay cavities.
  vtkSetClampMacro(MaxMarrowRadius, double, 0.0, 1e6);
  vtkGetMacro(MaxMarrowRadius, double);
  /// Keep bones as their surfaces enclose them: shells stay shells (default off). The report still
  /// gives each bone's shell and solid volumes.
  vtkSetMacro(HollowBones, bool);
  vtkGetMacro(HollowBones, bool);
  vtkBooleanMacro(HollowBones, bool);

  /// Optional lattice (origin, spacing, direction, extent) of the output; its scalars are not used.
  void SetReferenceImage(vtkImageData* image);
  vtkImageData* GetReferenceImage();

  /// Results of the last run.
  vtkGetCharFromStdStringMacro(LabelTableTSV);
  vtkGetCharFromStdStringMacro(Report);
  vtkGetMacro(NumberOfWarnings, int);
  vtkGetMacro(Seconds, double);

protected:
  vtkReposeMeshVoxelizer();
  ~vtkReposeMeshVoxelizer() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double VoxelSize = 1.0;
  double PaddingVoxels = 2.0;
  double MaxVoxels = 536870912.0;
  double MaxMarrowRadius = 30.0;
  bool HollowBones = false;
  vtkSmartPointer<vtkImageData> ReferenceImage;
  std::map<int, std::string> PartNames, PartSources;
  std::map<int, int> PartRoles;
  std::string LabelTableTSV;
  std::string Report;
  int NumberOfWarnings = 0;
  double Seconds = 0;

private:
  vtkReposeMeshVoxelizer(const vtkReposeMeshVoxelizer&) = delete;
  void operator=(const vtkReposeMeshVoxelizer&) = delete;
  std::string NameBuffer;
};

#endif
