#include "filter_errors.h"

#include <stdexcept>

#include <vtkAlgorithm.h>
#include <vtkExecutive.h>

namespace repose {

void ErrorCapture::Execute(vtkObject*, unsigned long, void* callData) {
  std::string text = callData ? static_cast<const char*>(callData) : "";
  const auto pos = text.find("): ");
  if (pos != std::string::npos) text = text.substr(pos + 3);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  for (char& c : text)
    if (c == '\n') c = ' ';
  last = text;
}

vtkSmartPointer<ErrorCapture> captureErrors(vtkAlgorithm* filter) {
  auto capture = vtkSmartPointer<ErrorCapture>::New();
  filter->AddObserver(vtkCommand::ErrorEvent, capture);
  return capture;
}

void requireOutput(bool ok, const std::string& what, const ErrorCapture* errors) {
  if (!ok)
    throw std::runtime_error(what + " failed" + (errors && !errors->last.empty() ? ": " + errors->last : std::string()));
}

std::optional<std::string> updateFilter(vtkAlgorithm* filter) {
  auto capture = vtkSmartPointer<ErrorCapture>::New();
  const unsigned long tag = filter->AddObserver(vtkCommand::ErrorEvent, capture);
  const int ok = filter->GetExecutive()->Update();
  filter->RemoveObserver(tag);
  if (ok && capture->last.empty()) return std::nullopt;
  return capture->last;
}

void updateOrThrow(vtkAlgorithm* filter, const std::string& what) {
  if (const auto error = updateFilter(filter))
    throw std::runtime_error(what + " failed" + (error->empty() ? std::string() : ": " + *error));
}

void updateOrThrowFor(vtkAlgorithm* filter, const std::string& file, const std::string& what) {
  if (const auto error = updateFilter(filter))
    throw std::runtime_error(file + ": " + what + (error->empty() ? std::string(" failed") : " (" + *error + ")"));
}

}  // namespace repose
