#ifndef vtkReposeAutoRig_h
#define vtkReposeAutoRig_h
// Automatic skeleton (repose::autoRig) from a label image's bone labels.
//
// Input port 0: label image (integer scalars; origin, spacing and direction honoured).
// Output port 0: the label image with every label holding several bones split (its largest
// component keeps the value, the others get new values); the skeleton refers to these values, so
// write this image together with the skeleton. Equal to the input when nothing was split.
// Fragments of bone labels take the value of the bone they went to (or, far from every bone, a new
// soft label); see repose::autoRig.
// After Update(): GetSkeletonJSON() (skeleton.json text, meant to be edited by hand),
// GetOutputLabelTableTSV() (the table with the split bones' names) and GetReport() (joints, bones
// cut by the field of view, bones left out, missing bones, fragments and where they went).

#include "ReposeFiltersModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class REPOSEFILTERS_EXPORT vtkReposeAutoRig : public vtkImageAlgorithm
{
public:
  static vtkReposeAutoRig* New();
  vtkTypeMacro(vtkReposeAutoRig, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Label table text: value<TAB>name[<TAB>kind] lines, or a 3D Slicer colour table ("value name
  /// R G B A" lines); empty (default) = TotalSegmentator's "total" class names.
  vtkSetStdStringFromCharMacro(LabelTableTSV);
  vtkGetCharFromStdStringMacro(LabelTableTSV);
  /// Where the table came from (a file name), for messages and the report's "label table:" line.
  vtkSetStdStringFromCharMacro(LabelTableName);
  vtkGetCharFromStdStringMacro(LabelTableName);
  /// Fail when the table's names contradict where its bones lie (default on): the wrong table.
  vtkSetMacro(CheckLabelTable, bool);
  vtkGetMacro(CheckLabelTable, bool);
  vtkBooleanMacro(CheckLabelTable, bool);

  /// Largest surface gap (mm) between adjacent bones (default 6); the limit is at least
  /// MaxGapVoxels (default 3.5, as repose::AutoRigOptions) voxels of the largest spacing.
  vtkSetClampMacro(MaxGapMm, double, 0.0, 1000.0);
  vtkGetMacro(MaxGapMm, double);
  vtkSetClampMacro(MaxGapVoxels, double, 0.0, 100.0);
  vtkGetMacro(MaxGapVoxels, double);

  /// Results of the last run.
  vtkGetCharFromStdStringMacro(SkeletonJSON);
  vtkGetCharFromStdStringMacro(Report);
  vtkGetCharFromStdStringMacro(OutputLabelTableTSV);
  vtkGetMacro(NumberOfJoints, int);
  vtkGetMacro(Seconds, double);
  /// Fragments given to a bone, and their voxels; fragment voxels left as soft tissue.
  vtkGetMacro(NumberOfReassignedFragments, int);
  vtkGetMacro(ReassignedFragmentVoxels, vtkIdType);
  vtkGetMacro(UnassignedFragmentVoxels, vtkIdType);

protected:
  vtkReposeAutoRig();
  ~vtkReposeAutoRig() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::string LabelTableTSV;
  std::string LabelTableName;
  bool CheckLabelTable = true;
  double MaxGapMm = 6.0;
  double MaxGapVoxels = 3.5;
  std::string SkeletonJSON;
  std::string Report;
  std::string OutputLabelTableTSV;
  int NumberOfJoints = 0;
  double Seconds = 0;
  int NumberOfReassignedFragments = 0;
  vtkIdType ReassignedFragmentVoxels = 0;
  vtkIdType UnassignedFragmentVoxels = 0;

private:
  vtkReposeAutoRig(const vtkReposeAutoRig&) = delete;
  void operator=(const vtkReposeAutoRig&) = delete;
};

#endif
