#include "label_export.h"

#include <vtkDataObject.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkStringArray.h>

namespace repose {

std::string labelTablePathFor(const std::string& imagePath) {
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd", ".vdb"}) {
    const std::string e = ext;
    if (imagePath.size() > e.size() && imagePath.compare(imagePath.size() - e.size(), e.size(), e) == 0)
      return imagePath.substr(0, imagePath.size() - e.size()) + ".tsv";
  }
  return imagePath + ".tsv";
}

void addLabelNames(vtkDataObject* data, const LabelTable& table) {
  if (table.labels.empty()) return;
  auto values = vtkSmartPointer<vtkIntArray>::New();
  values->SetName("LabelValue");
  auto names = vtkSmartPointer<vtkStringArray>::New();
  names->SetName("LabelName");
  for (const LabelInfo& l : table.labels) {
    values->InsertNextValue(l.value);
    names->InsertNextValue(l.name);
  }
  data->GetFieldData()->AddArray(values);
  data->GetFieldData()->AddArray(names);
}

}  // namespace repose
