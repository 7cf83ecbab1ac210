#include "vtkReposeWriterBase.h"

#include "vtkInformation.h"

#include "temporary_lock.h"
#include "written_file.h"

#include <filesystem>
#include <memory>
#include <unistd.h>

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

int vtkReposeWriterBase::WriteAtomically(const std::function<void(const std::string& path)>& write)
{
  namespace fs = std::filesystem;
  if (!this->FileName || !*this->FileName)
  {
    return this->Fail("no file name set");
  }
  fs::path target(this->FileName);
  if (target.filename().empty())
  {
    target = target.parent_path(); // "folder/"
  }
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
  {
    return this->Fail("directory " + dir.string() + " does not exist");
  }
  if (fs::exists(target, ec))
  {
    return this->Fail("it exists already");
  }
  const fs::path tmpDir =
    dir / (".repose-tmp-" + std::to_string(::getpid()) + "-" + target.filename().string() + ".d");
  const fs::path tmp = tmpDir / target.filename();
  try
  {
    const repose::TemporaryLock lock(tmpDir.string(), true);
    try
    {
      write(tmp.string());
      repose::requireWritten(target.string(), tmp.string(), 1);
      fs::rename(tmp, target);
      fs::remove(tmpDir);
    }
    catch (...)
    {
      fs::remove_all(tmpDir, ec);
      throw;
    }
  }
  catch (const repose::WriteFailure& e)
  {
    return this->Fail(e.reason);
  }
  catch (const std::exception& e)
  {
    return this->Fail(e.what());
  }
  return 1;
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
