#pragma once
// VTK writers checked to the last byte. A writer can meet a full disk and still return 1 (its
// std::ofstream loses the last buffer on close), so besides Write()'s result and the error code
// the file must end with the bytes its format ends with, and be flushed to the disk.
#include <cerrno>
#include <string>
#include <type_traits>

#include <vtkSmartPointer.h>

#include "vtkReposeVersion.h"

namespace repose {

/// The last bytes of a VTK XML file and of a PNG picture (its IEND chunk).
extern const std::string kVtkXmlTail, kPngTail;

/// Throws WriteFailure "PATH: cannot write (REASON)" unless the write succeeded, the file ends with
/// `tail` ("" skips that) and it is on the disk.
void checkWritten(int written, unsigned long errorCode, int err, const std::string& path, const std::string& tail);

/// Silences stderr while it lives (unless REPOSE_VERBOSE is set): ITK's NIfTI library prints a
/// failed write in lines of its own ("** ERROR: NWAD ..."), which the caller reports in one line.
class QuietStderr {
public:
  QuietStderr();
  ~QuietStderr();
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

private:
  int saved_ = -1;
};

/// A shallow copy of `data` whose field data carries ReposeVersion (vtkReposeVersion), for the VTK
/// XML writers: the file says which Repose wrote it, the pipeline's output is left as it is.
template <class Data>
vtkSmartPointer<Data> withVersion(Data* data) {
  auto copy = vtkSmartPointer<Data>::New();
  copy->ShallowCopy(data);
  vtkReposeVersion::Stamp(copy);
  return copy;
}

/// Runs `writer->Write()` (a VTK writer whose file name is set) and checks it as above.
template <class Writer>
void writeChecked(Writer* writer, const std::string& path, const std::string& tail) {
  errno = 0;
  int written = 1;  // vtkImageWriter::Write() returns nothing: its error code tells
  if constexpr (std::is_void_v<decltype(writer->Write())>)
    writer->Write();
  else
    written = writer->Write();
  checkWritten(written, writer->GetErrorCode(), errno, path, tail);
}

/// Writes `data` with a VTK XML writer (appended raw binary, the version stamped) and checks it.
template <class Writer, class Data>
void writeVtkXml(Data* data, const std::string& path) {
  auto writer = vtkSmartPointer<Writer>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputData(withVersion(data));
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writeChecked(writer.Get(), path, kVtkXmlTail);
}

}  // namespace repose
