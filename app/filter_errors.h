#pragma once
// Running a VTK filter from the app: its own error text (what the core threw, reported through
// vtkErrorMacro) turned into one std::runtime_error line instead of VTK's console output.
#include <optional>
#include <string>

#include <vtkCommand.h>
#include <vtkSmartPointer.h>

class vtkAlgorithm;

namespace repose {

/// Records the last error a filter reported, as one line without VTK's "(0x...): " prefix.
class ErrorCapture : public vtkCommand {
public:
  static ErrorCapture* New() { return new ErrorCapture; }
  void Execute(vtkObject*, unsigned long, void* callData) override;
  std::string last;
};

/// An ErrorCapture observing `filter` for as long as the filter lives.
vtkSmartPointer<ErrorCapture> captureErrors(vtkAlgorithm* filter);
/// Throws std::runtime_error "`what` failed[: the filter's error]" unless `ok`.
void requireOutput(bool ok, const std::string& what, const ErrorCapture* errors);

/// Runs a VTK filter: nothing when it ran, its own error message ("" when it gave none) when it failed.
std::optional<std::string> updateFilter(vtkAlgorithm* filter);
/// Runs a VTK filter; throws std::runtime_error "`what` failed: <the filter's own error>" on failure.
void updateOrThrow(vtkAlgorithm* filter, const std::string& what);
/// Same, for a filter working on one file: throws "FILE: what (<the filter's own error>)".
void updateOrThrowFor(vtkAlgorithm* filter, const std::string& file, const std::string& what);

}  // namespace repose
