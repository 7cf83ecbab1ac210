#include "relaxation_words.h"

#include "corotational_fem.h"
#include "relaxation_regions.h"

namespace repose {

const std::vector<RelaxationWord>& relaxationWords(const std::string& setting) {
  static const std::vector<RelaxationWord> model = {{"fixed-corotated", CorotationalOptions::FixedCorotated},
                                                    {"linear", CorotationalOptions::Linear}};
  static const std::vector<RelaxationWord> volume = {{"tissues", int(VolumeRegionChoice::Tissues)},
                                                     {"segments", int(VolumeRegionChoice::Segments)},
                                                     {"body", int(VolumeRegionChoice::Body)},
                                                     {"none", int(VolumeRegionChoice::None)}};
  static const std::vector<RelaxationWord> continuation = {{"if-inverted", CorotationalOptions::IfInverted},
                                                           {"never", CorotationalOptions::Never},
                                                           {"always", CorotationalOptions::Always}};
  static const std::vector<RelaxationWord> none;
  return setting == "model" ? model : setting == "volume" ? volume : setting == "continuation" ? continuation : none;
}

int relaxationWordValue(const std::string& setting, const std::string& word) {
  for (const RelaxationWord& w : relaxationWords(setting))
    if (word == w.word) return w.value;
  return -1;
}

}  // namespace repose
