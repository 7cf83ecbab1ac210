#pragma once
// The label table a label volume is read with: --label-table, else the table beside the volume,
// else the built-in TotalSegmentator names.
#include <string>

#include "label_table.h"

class vtkImageData;

namespace repose {

struct LabelTableChoice {
  LabelTable table;
  std::string text;    // the file's text; empty for the built-in names
  std::string path;    // the file; empty for the built-in names
  std::string origin;  // for the console
  std::string option;  // how the user gives a table, for messages: "--label-table" or the GUI's field
};

/// labelTablePath (--label-table; "" = none given), else the first table beside labelsPath that holds one (see labelTablesBeside;
/// a NAME.txt that holds none is skipped with a note), else the built-in TotalSegmentator names.
/// Throws std::runtime_error "FILE: ..." for a table file that holds no labels. `option` names how the
/// user gives a table in the messages that ask for one.
LabelTableChoice chooseLabelTable(const std::string& labelsPath, const std::string& labelTablePath,
                                  const std::string& option = "--label-table");

/// A table whose bone names contradict where the bones lie is the wrong table: throws
/// std::runtime_error saying so, naming the table and the volume.
void requireTableFits(vtkImageData* labels, const std::string& labelsPath, const LabelTableChoice& c);

/// The label table kept in a case prepared from a hand-written skeleton, as TSV: the chosen table;
/// the built-in TotalSegmentator names (of the values present) only when they fit the volume; else ""
/// (the case then names its labels label_<value>, see Pipeline::saveCase). Says which on stdout.
std::string caseLabelTable(vtkImageData* labels, const std::string& labelsPath, const std::string& labelTablePath,
                           const std::string& option = "--label-table");

}  // namespace repose
