#ifndef vtkReposeWriterBase_h
#define vtkReposeWriterBase_h
// What Repose's image writers share: a file (or folder) name, Write() that updates the input and
// writes it, and one-line errors "NAME: cannot write (REASON)" kept for GetLastError().

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

#include <functional>
#include <string>

class REPOSEVOLUME_EXPORT vtkReposeWriterBase : public vtkImageAlgorithm
{
public:
  vtkAbstractTypeMacro(vtkReposeWriterBase, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// Updates the input and writes it. Returns 1 on success, 0 on failure (see GetLastError()).
  int Write();

  /// One-line description of the last failure ("NAME: cannot write (reason)"), empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeWriterBase();
  ~vtkReposeWriterBase() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  /// Records "NAME: cannot write (reason)", reports it through vtkErrorMacro and returns 0.
  int Fail(const std::string& reason);
  /// Writes FileName atomically: `write` is given a path inside a locked temporary folder beside it
  /// (.repose-tmp-<pid>-NAME.d/NAME, see temporary_lock.h) to write a file or a folder at; the result
  /// is flushed to the disk and renamed into place, the temporary folder removed. An exception of
  /// `write` (its what() the reason) or a failed check leaves nothing. Returns 1, or Fail's 0.
  int WriteAtomically(const std::function<void(const std::string& path)>& write);

  char* FileName = nullptr;
  std::string LastError;

private:
  vtkReposeWriterBase(const vtkReposeWriterBase&) = delete;
  void operator=(const vtkReposeWriterBase&) = delete;
};

#endif
