#pragma once
// The words of the relaxation's settings, as users type them (`repose pose --relax-model linear`,
// a batch manifest's `relax: {model: linear}`): one table, so the CLI, the batch and the Python
// filter accept and list the same words.
#include <string>
#include <vector>

namespace repose {

/// A word and the value it stands for: CorotationalOptions::Model for "model",
/// VolumeRegionChoice for "volume", CorotationalOptions::Continuation for "continuation".
struct RelaxationWord {
  const char* word;
  int value;
};

/// The words of a setting ("model", "volume" or "continuation"), in the order messages list them;
/// empty for another setting.
const std::vector<RelaxationWord>& relaxationWords(const std::string& setting);

/// The value `word` stands for in `setting`, or -1 when it is not one of its words.
int relaxationWordValue(const std::string& setting, const std::string& word);

}  // namespace repose
