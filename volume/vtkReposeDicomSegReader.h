#ifndef vtkReposeDicomSegReader_h
#define vtkReposeDicomSegReader_h
// Reads a binary DICOM Segmentation onto the lattice of a reference image (input 0, e.g. the CT it
// was made on): an int label volume, each voxel the value of the segment covering it (by name
// through AddSegment, else the segment number), 0 elsewhere. Frames that are not slices of that
// lattice are an error. The segment names, in segment-number order, are in the output's field
// data "SegmentNames".

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

#include <memory>
#include <string>

class REPOSEVOLUME_EXPORT vtkReposeDicomSegReader : public vtkImageAlgorithm
{
public:
  static vtkReposeDicomSegReader* New();
  vtkTypeMacro(vtkReposeDicomSegReader, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// The value a segment of this name gets.
  void AddSegment(int value, const char* name);
  void RemoveAllSegments();

  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeDicomSegReader();
  ~vtkReposeDicomSegReader() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  std::string LastError;
  struct Segments;
  std::unique_ptr<Segments> Table;

private:
  vtkReposeDicomSegReader(const vtkReposeDicomSegReader&) = delete;
  void operator=(const vtkReposeDicomSegReader&) = delete;
};

#endif
