#pragma once
// JSON text as every reader of the project parses it: a bounded nesting depth (deep nesting must be
// an error message, not a stack overflow) and one-line errors a caller prefixes with the file name.
#include <string>

#include <json/value.h>

namespace repose {

/// Parses `text`; with `specialFloats` NaN/Infinity parse so the caller can say which value is bad.
/// Nesting deeper than 256 levels is refused. Throws std::invalid_argument("malformed JSON: ...")
/// on one line.
Json::Value parseJsonText(const std::string& text, bool specialFloats);

}  // namespace repose
