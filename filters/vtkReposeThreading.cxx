#include "vtkReposeThreading.h"

#include "vtkObjectFactory.h"
#include "vtkSMPTools.h"

#include "parallel_for.h"

vtkStandardNewMacro(vtkReposeThreading);

namespace
{
struct RangeFunctor
{
  const repose::RangeBody* Body;
  void operator()(vtkIdType begin, vtkIdType end) const
  {
    (*this->Body)(static_cast<std::size_t>(begin), static_cast<std::size_t>(end));
  }
};

// Installed when the library is loaded, so every filter's core call is threaded by vtkSMPTools.
struct AutoInstall
{
  AutoInstall() { vtkReposeThreading::Install(); }
} autoInstall;
}

void vtkReposeThreading::Install()
{
  repose::setParallelRunner([](std::size_t n, std::size_t grain, const repose::RangeBody& body) {
    RangeFunctor functor{ &body };
    vtkSMPTools::For(0, static_cast<vtkIdType>(n), static_cast<vtkIdType>(grain), functor);
  });
}

void vtkReposeThreading::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
}
