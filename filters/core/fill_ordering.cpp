#include "fill_ordering.h"

#include <cholmod.h>

namespace repose {

bool metisPays(double amdFlops, long rows, double factorizations) {
  // METIS needs 0.43-0.75 of AMD's flops on these tet meshes but takes 4-8 times AMD's ordering
  // time: the two balance near 1e5 of AMD's flops per row (medium phantom, 0.95e5:
  // AMD 7.1-8.6 s, METIS 8.9 s; Visible Human female at 2 mm, 1.06e5: 11.0 and 11.5 CPU s). Automatic
  // has already paid for AMD's analysis when it turns to METIS, hence the margin.
  constexpr double kMetisPaysAboveFlopsPerRow = 1.5e5;
  return amdFlops * factorizations > kMetisPaysAboveFlopsPerRow * double(rows);
}

void setFillOrdering(cholmod_common_struct& common, FillOrdering ordering) {
  common.method[0].ordering = ordering == FillOrdering::Metis ? CHOLMOD_METIS
                              : ordering == FillOrdering::CholmodDefault ? CHOLMOD_GIVEN  // the default's first slot
                                                                         : CHOLMOD_AMD;
  common.nmethods = ordering == FillOrdering::CholmodDefault ? 0 : 1;
}

namespace {
const char* orderingName(int ordering) {
  switch (ordering) {
    case CHOLMOD_NATURAL: return "natural";
    case CHOLMOD_GIVEN: return "given";
    case CHOLMOD_AMD: return "AMD";
    case CHOLMOD_METIS: return "METIS";
    case CHOLMOD_NESDIS: return "NESDIS";
    case CHOLMOD_COLAMD: return "COLAMD";
    case CHOLMOD_POSTORDERED: return "postordered";
    default: return "other";
  }
}
}  // namespace

FillAnalysis lastFillAnalysis(const cholmod_common_struct& common) {
  FillAnalysis a;
  if (common.selected < 0 || common.selected >= CHOLMOD_MAXMETHODS) return a;
  const auto& method = common.method[common.selected];
  a.ordering = orderingName(method.ordering);
  a.flops = method.fl;
  a.factorNonzeros = method.lnz;
  return a;
}

}  // namespace repose
