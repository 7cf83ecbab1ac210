#ifndef vtkReposeThreading_h
#define vtkReposeThreading_h
// Routes the numeric core's parallel loops through vtkSMPTools.

#include "ReposeFiltersModule.h"
#include "vtkObject.h"

class REPOSEFILTERS_EXPORT vtkReposeThreading : public vtkObject
{
public:
  static vtkReposeThreading* New();
  vtkTypeMacro(vtkReposeThreading, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Makes repose::parallelFor use vtkSMPTools. Done automatically when the module loads.
  static void Install();

protected:
  vtkReposeThreading() = default;
  ~vtkReposeThreading() override = default;

private:
  vtkReposeThreading(const vtkReposeThreading&) = delete;
  void operator=(const vtkReposeThreading&) = delete;
};

#endif
