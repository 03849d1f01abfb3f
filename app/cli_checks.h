// Command-line checks shared by candela and candela-cli.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace candela {

// A finite number > 0. CLI::PositiveNumber and CLI::Range let NaN through (every comparison with
// NaN is false), so `--time nan` would silently mean "no time".
inline CLI::Validator finitePositive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || !(v > 0.0)) return "expected a finite number > 0, got " + text;
        return {};
      },
      "POSITIVE");
}

}  // namespace candela
