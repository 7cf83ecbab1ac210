#include "vtkReposeWriterBase.h"

#include "vtkInformation.h"

vtkReposeWriterBase::vtkReposeWriterBase()
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(0);
}

vtkReposeWriterBase::~vtkReposeWriterBase()
{
  this->SetFileName(nullptr);
}

int vtkReposeWriterBase::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkReposeWriterBase::FillOutputPortInformation(int, vtkInformation*)
{
  return 1;
}

int vtkReposeWriterBase::Fail(const std::string& reason)
{
  const bool named = this->FileName && *this->FileName;
  this->LastError = (named ? std::string(this->FileName) : std::string("(no file name)")) + ": cannot write (" +
    reason + ")";
  vtkErrorMacro(<< this->LastError);
  return 0;
}

int vtkReposeWriterBase::Write()
{
  this->LastError.clear();
  if (this->GetNumberOfInputConnections(0) < 1)
  {
    return this->Fail("no input");
  }
  this->Modified();
  this->Update();
  return this->LastError.empty() ? 1 : 0;
}

void vtkReposeWriterBase::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "LastError: " << this->LastError << "\n";
}
