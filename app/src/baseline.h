#pragma once
// The baseline that `bench --baseline FILE` compares with: the JSON of an earlier `bench --json`.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace lp::cli {

/// Parses a baseline's text (the whole of it: trailing text is an error). It must hold a positive
/// finite `calibration_ms` and, under `stages`, an object of stages each with a finite,
/// non-negative `median_ms`. Throws lp::Error naming `name` and the fault.
nlohmann::json parseBaseline(std::string_view text, const std::string& name);

}  // namespace lp::cli
