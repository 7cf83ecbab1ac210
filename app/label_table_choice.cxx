#include "label_table_choice.h"

#include <algorithm>
#include <iostream>
#include <set>
#include <stdexcept>

#include <vtkImageData.h>

#include "ReposeImageConversion.h"
#include "atomic_outputs.h"
#include "label_table_fit.h"

namespace repose {
namespace {

LabelTableChoice builtinLabelTable(const std::string& labelsPath, const std::string& option) {
  LabelTableChoice c;
  c.table = builtinTotalSegmentatorTable();
  c.origin = "built-in TotalSegmentator names (no " + option + " given, none found beside " + labelsPath + ")";
  c.option = option;
  return c;
}

/// Reads a label table; a file that holds none is an error naming it.
LabelTable readLabelTable(const std::string& path, const std::string& text) {
  LabelTable table;
  try {
    table = parseLabelTable(text, path);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  if (table.labels.empty())
    throw std::runtime_error(path + ": holds no labels (expected value<TAB>name[<TAB>kind] or value name R G B A lines)");
  return table;
}

}  // namespace

LabelTableChoice chooseLabelTable(const std::string& labelsPath, const std::string& labelTablePath,
                                  const std::string& option) {
  LabelTableChoice c;
  c.option = option;
  if (!labelTablePath.empty()) {
    c.path = labelTablePath;
    c.text = readTextFile(c.path);
    c.table = readLabelTable(c.path, c.text);
    c.origin = c.path;
    return c;
  }
  for (const std::string& path : labelTablesBeside(labelsPath)) {
    c.path = path;
    c.text = readTextFile(path);
    try {
      c.table = readLabelTable(path, c.text);
    } catch (const std::runtime_error& e) {
      // NAME.txt beside the volume may be notes rather than a Slicer colour table: not an error.
      if (imageExtension(path) != ".txt") throw;
      std::cout << "label table: ignoring " << path << " (" << e.what() << ")" << std::endl;
      continue;
    }
    c.origin = path + " (found beside " + labelsPath + ")";
    return c;
  }
  return builtinLabelTable(labelsPath, option);
}

void requireTableFits(vtkImageData* labels, const std::string& labelsPath, const LabelTableChoice& c) {
  LabelVolume volume;
  if (!repose_vtk::ToVolume(labels, volume)) throw std::runtime_error(labelsPath + ": not a label volume");
  const LabelTableFit fit = checkLabelTableFit(volume, c.table);
  if (fit.fits()) return;
  if (c.path.empty())
    throw std::runtime_error(labelsPath + ": the built-in TotalSegmentator names do not fit it (no " + c.option +
                             " given, none found beside it): " + fit.problem() + "; give its label table with " + c.option);
  throw std::runtime_error(c.path + ": does not fit " + labelsPath + ": " + fit.problem() +
                           "; give the volume's own label table with " + c.option);
}

std::string caseLabelTable(vtkImageData* labels, const std::string& labelsPath, const std::string& labelTablePath,
                           const std::string& option) {
  const LabelTableChoice c = chooseLabelTable(labelsPath, labelTablePath, option);
  if (!c.path.empty()) {
    std::cout << "label table: " << c.origin << std::endl;
    return labelTableToTsv(c.table);
  }
  LabelVolume volume;
  if (!repose_vtk::ToVolume(labels, volume)) return "";
  const std::set<int> present(volume.data.begin(), volume.data.end());
  const LabelTableFit fit = checkLabelTableFit(volume, c.table);
  const bool named = fit.checked >= 3 && fit.fits() &&
                     std::all_of(present.begin(), present.end(), [&](int v) { return v == 0 || c.table.find(v); });
  if (!named) {
    std::cout << "label table: none given or found beside " << labelsPath << "; the case names its labels label_<value>"
              << std::endl;
    return "";
  }
  LabelTable table;
  for (const LabelInfo& l : c.table.labels)
    if (present.count(l.value)) table.labels.push_back(l);
  std::cout << "label table: " << c.origin << std::endl;
  return labelTableToTsv(table);
}

}  // namespace repose
