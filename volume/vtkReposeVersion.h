#ifndef vtkReposeVersion_h
#define vtkReposeVersion_h
// The version `repose --version` prints, for the metadata of every file Repose writes: NIfTI's
// descrip ("Repose 0.1.0 labels"), NRRD and MetaImage key/value fields and VTK XML field data
// ("ReposeVersion" = "0.1.0"). One source, the project's VERSION, for C++ and Python alike (the
// batch writes its files through Python and must write the same bytes as `repose pose`).

#include "ReposeVolumeModule.h"
#include "vtkObject.h"

class vtkDataObject;

class REPOSEVOLUME_EXPORT vtkReposeVersion : public vtkObject
{
public:
  static vtkReposeVersion* New();
  vtkTypeMacro(vtkReposeVersion, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// "0.1.0".
  static const char* GetVersion();
  /// The name of the key or field-data array that carries it: "ReposeVersion".
  static const char* GetKey();
  /// Adds (or replaces) a one-value string array GetKey() = GetVersion() in the field data.
  /// Stamp a shallow copy, not a pipeline's output: the copy's field data is its own.
  static void Stamp(vtkDataObject* data);

protected:
  vtkReposeVersion() = default;
  ~vtkReposeVersion() override = default;

private:
  vtkReposeVersion(const vtkReposeVersion&) = delete;
  void operator=(const vtkReposeVersion&) = delete;
};

#endif
