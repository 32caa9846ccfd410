// strict_json_dom.h - the strict JSON check (vff/strict_json.h) that also keeps the value it read,
// for the readers of libvff that go on to check the document's values.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "vff/strict_json.h"

namespace vff::detail {

// Parses `text` by the rules of vff/strict_json.h into `out`; the first problem, or nothing. `out`
// is meaningful only when nothing is returned.
std::optional<JsonTextProblem> parseStrictJson(std::string_view text, nlohmann::json& out);

}  // namespace vff::detail
