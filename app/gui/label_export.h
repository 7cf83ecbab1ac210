#pragma once
// Label names travel with what the GUI exports: a label volume gets its table beside it
// (posed_labels.nii.gz -> posed_labels.tsv, `value<TAB>name<TAB>kind` as label_table.h reads), and
// meshes and surfaces carry the table as field data (LabelValue, LabelName), which ParaView shows.
#include <string>

#include <vtkSmartPointer.h>

#include "label_table.h"

class vtkDataObject;

namespace repose {

/// The table's file name for an image path: the name without its image extension, plus ".tsv".
std::string labelTablePathFor(const std::string& imagePath);
/// Adds (replaces) the LabelValue and LabelName field data arrays; nothing for an empty table.
void addLabelNames(vtkDataObject* data, const LabelTable& table);
/// A shallow copy of `data` with field data arrays LabelValue (int) and LabelName (string).
template <class T>
vtkSmartPointer<T> withLabelNames(T* data, const LabelTable& table) {
  auto copy = vtkSmartPointer<T>::New();
  copy->ShallowCopy(data);
  addLabelNames(copy, table);
  return copy;
}

}  // namespace repose
