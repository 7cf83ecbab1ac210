// The rest CT warped by ITK's own WarpImageFilter through Repose's displacement field, compared with
// Repose's posed CT: an independent check that the field is the map the posed CT was pulled through.
//
// usage: repose_itk_warp_compare REST_CT DISPLACEMENT_FIELD POSED_CT
// Prints one line: "voxels N median M p999 P over1 K max X" over the voxels the field maps (non-zero
// displacement), differences in the CT's units (HU); exit status 1 when a file cannot be read or the
// grids differ.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <vector>

#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageRegionConstIterator.h>
#include <itkLinearInterpolateImageFunction.h>
#include <itkMetaImageIOFactory.h>
#include <itkNiftiImageIOFactory.h>
#include <itkNrrdImageIOFactory.h>
#include <itkVector.h>
#include <itkWarpImageFilter.h>

using Image = itk::Image<float, 3>;
using Field = itk::Image<itk::Vector<float, 3>, 3>;

template <class T>
typename T::Pointer read(const char* path) {
  auto reader = itk::ImageFileReader<T>::New();
  reader->SetFileName(path);
  reader->Update();
  return reader->GetOutput();
}

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s REST_CT DISPLACEMENT_FIELD POSED_CT\n", argv[0]);
    return 1;
  }
  itk::NiftiImageIOFactory::RegisterOneFactory();
  itk::NrrdImageIOFactory::RegisterOneFactory();
  itk::MetaImageIOFactory::RegisterOneFactory();
  try {
    const Image::Pointer rest = read<Image>(argv[1]);
    const Field::Pointer field = read<Field>(argv[2]);
    const Image::Pointer posed = read<Image>(argv[3]);
    if (field->GetLargestPossibleRegion() != posed->GetLargestPossibleRegion() ||
        (field->GetOrigin() - posed->GetOrigin()).GetNorm() > 1e-4) {
      std::fprintf(stderr, "the displacement field and the posed CT are on different grids\n");
      return 1;
    }
    auto warp = itk::WarpImageFilter<Image, Image, Field>::New();
    warp->SetInput(rest);
    warp->SetDisplacementField(field);
    warp->SetInterpolator(itk::LinearInterpolateImageFunction<Image, double>::New());
    warp->SetOutputParametersFromImage(posed);
    warp->SetEdgePaddingValue(-1024.0f);
    warp->Update();
    std::vector<double> diff;
    itk::ImageRegionConstIterator<Field> f(field, field->GetLargestPossibleRegion());
    itk::ImageRegionConstIterator<Image> w(warp->GetOutput(), field->GetLargestPossibleRegion());
    itk::ImageRegionConstIterator<Image> p(posed, field->GetLargestPossibleRegion());
    for (; !f.IsAtEnd(); ++f, ++w, ++p)
      if (f.Get().GetNorm() > 0) diff.push_back(std::fabs(double(w.Get()) - double(p.Get())));
    if (diff.empty()) {
      std::fprintf(stderr, "the displacement field maps no voxel\n");
      return 1;
    }
    std::sort(diff.begin(), diff.end());
    const std::size_t over1 = std::size_t(diff.end() - std::upper_bound(diff.begin(), diff.end(), 1.0));
    std::printf("voxels %zu median %.6g p999 %.6g over1 %zu max %.6g\n", diff.size(), diff[diff.size() / 2],
                diff[std::min(diff.size() - 1, std::size_t(0.999 * double(diff.size())))], over1, diff.back());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
