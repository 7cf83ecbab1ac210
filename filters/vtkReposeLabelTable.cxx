#include "vtkReposeLabelTable.h"

#include "vtkObjectFactory.h"

#include <stdexcept>

#include "label_table.h"

vtkStandardNewMacro(vtkReposeLabelTable);

struct vtkReposeLabelTable::Table
{
  repose::LabelTable table;
};

vtkReposeLabelTable::vtkReposeLabelTable()
  : Labels(new Table)
{
}

vtkReposeLabelTable::~vtkReposeLabelTable() = default;

int vtkReposeLabelTable::SetTableText(const char* text, const char* name)
{
  this->LastError.clear();
  try
  {
    this->Labels->table = repose::parseLabelTable(text ? text : "", name ? name : "label table");
  }
  catch (const std::invalid_argument& e)
  {
    this->Labels->table = repose::LabelTable();
    this->LastError = e.what();
    return 0;
  }
  this->Modified();
  return 1;
}

int vtkReposeLabelTable::GetNumberOfLabels()
{
  return static_cast<int>(this->Labels->table.labels.size());
}

std::string vtkReposeLabelTable::GetTsv()
{
  return repose::labelTableToTsv(this->Labels->table);
}

std::string vtkReposeLabelTable::GetSlicerColorTable()
{
  return repose::labelTableToSlicerColorTable(this->Labels->table);
}

void vtkReposeLabelTable::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfLabels: " << this->Labels->table.labels.size() << "\n";
}
