#include "json_text.h"

#include <memory>
#include <stdexcept>

#include <json/reader.h>

namespace repose {
namespace {

std::string oneLine(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    if (c != ' ' || (!out.empty() && out.back() != ' ')) out += c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

}  // namespace

Json::Value parseJsonText(const std::string& text, bool specialFloats) {
  Json::CharReaderBuilder builder;
  builder["collectComments"] = false;
  builder["allowSpecialFloats"] = specialFloats;
  builder["stackLimit"] = 256;
  std::unique_ptr<Json::CharReader> reader(builder.newCharReader());
  Json::Value root;
  std::string errors;
  try {
    if (!reader->parse(text.data(), text.data() + text.size(), &root, &errors))
      throw std::invalid_argument("malformed JSON: " + oneLine(errors));
  } catch (const Json::Exception& e) {
    throw std::invalid_argument("malformed JSON: " + oneLine(e.what()) + " (nested too deeply)");
  }
  return root;
}

}  // namespace repose
