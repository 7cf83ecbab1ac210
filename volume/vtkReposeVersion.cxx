#include "vtkReposeVersion.h"

#include "vtkDataObject.h"
#include "vtkFieldData.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkStringArray.h"

#include "repose_version.h"

vtkStandardNewMacro(vtkReposeVersion);

const char* vtkReposeVersion::GetVersion()
{
  return REPOSE_VERSION;
}

const char* vtkReposeVersion::GetKey()
{
  return "ReposeVersion";
}

void vtkReposeVersion::Stamp(vtkDataObject* data)
{
  if (!data)
  {
    return;
  }
  if (!data->GetFieldData())
  {
    vtkNew<vtkFieldData> fields;
    data->SetFieldData(fields);
  }
  vtkNew<vtkStringArray> version;
  version->SetName(GetKey());
  version->InsertNextValue(GetVersion());
  data->GetFieldData()->AddArray(version);
}

void vtkReposeVersion::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Version: " << GetVersion() << "\n";
}
