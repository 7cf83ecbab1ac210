#ifndef vtkReposeLabelTable_h
#define vtkReposeLabelTable_h
// A label table (label value -> name, tissue kind, colour) as the files that travel beside a label
// volume, for scripts: SetTableText with the text of labels.tsv or a 3D Slicer .ctbl/.txt, then
// GetTsv (Repose's TSV, as `repose pose` writes posed_labels.tsv) or GetSlicerColorTable (as it
// writes posed_labels.ctbl). Errors: SetTableText returns 0 and GetLastError() holds one line.

#include "ReposeFiltersModule.h"
#include "vtkObject.h"

#include <memory>
#include <string>

class REPOSEFILTERS_EXPORT vtkReposeLabelTable : public vtkObject
{
public:
  static vtkReposeLabelTable* New();
  vtkTypeMacro(vtkReposeLabelTable, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Parses a table; `name` (a file) leads the error. 1 on success.
  int SetTableText(const char* text, const char* name);
  int GetNumberOfLabels();
  std::string GetTsv();
  std::string GetSlicerColorTable();
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeLabelTable();
  ~vtkReposeLabelTable() override;

private:
  vtkReposeLabelTable(const vtkReposeLabelTable&) = delete;
  void operator=(const vtkReposeLabelTable&) = delete;

  struct Table;
  std::unique_ptr<Table> Labels;
  std::string LastError;
};

#endif
