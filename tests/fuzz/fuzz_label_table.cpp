// Label tables (labels.tsv, 3D Slicer .ctbl/.txt): parsed; an accepted table written as Repose's TSV
// and as a Slicer colour table reads back with the same values and names.
#include "fuzz_input.h"
#include "label_table.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  repose::LabelTable table;
  try {
    table = repose::parseLabelTable(fuzzText(data, size), "fuzz.tsv");
  } catch (const std::invalid_argument&) {
    return 0;
  }
  const repose::LabelTable tsv = repose::parseLabelTable(repose::labelTableToTsv(table));
  if (tsv.labels.size() != table.labels.size()) fuzzInvariantBroken("the TSV does not read back");
  for (std::size_t i = 0; i < table.labels.size(); ++i)
    if (tsv.labels[i].value != table.labels[i].value || tsv.labels[i].name != table.labels[i].name ||
        tsv.labels[i].kind != table.labels[i].kind)
      fuzzInvariantBroken("a label does not read back from the TSV");
  const repose::LabelTable ctbl = repose::parseLabelTable(repose::labelTableToSlicerColorTable(table));
  for (const repose::LabelInfo& l : table.labels)
    if (l.value != 0 && !ctbl.find(l.value)) fuzzInvariantBroken("a label is missing from the colour table");
  return 0;
}
