#include "input_limits.h"

#include "fields.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace candela {

namespace {

// CANDELA_MAX_MEMORY_GB as the --max-memory flag reads it: a finite number of GB above 0, whole.
bool parseGb(const char* text, double& gb) {
  char* end = nullptr;
  gb = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(gb) && gb > 0.0 && gb * 1073741824.0 < 1.8e19;
}

size_t defaultBudget() {
  double gb = 0.0;
  if (const char* env = std::getenv("CANDELA_MAX_MEMORY_GB"); env && *env && parseGb(env, gb)) return static_cast<size_t>(gb * 1073741824.0);
  return size_t{4} << 30;
}

std::atomic<size_t>& budget() {
  static std::atomic<size_t> b{defaultBudget()};
  return b;
}

}  // namespace

void checkMemoryBudgetEnvironment() {
  const char* env = std::getenv("CANDELA_MAX_MEMORY_GB");
  double gb = 0.0;
  if (env && !parseGb(env, gb))
    throw InputError(std::string("CANDELA_MAX_MEMORY_GB: expected a finite number of GB above 0, as --max-memory takes (e.g. 8), got \"") +
                     std::string(env).substr(0, 40) + "\"");
}

size_t memoryBudgetBytes() { return budget().load(); }
void setMemoryBudgetBytes(size_t bytes) { budget().store(bytes); }

std::string formatBytes(double bytes) {
  char buf[64];
  if (bytes >= 1073741824.0)
    std::snprintf(buf, sizeof buf, "%.3g GB", bytes / 1073741824.0);
  else
    std::snprintf(buf, sizeof buf, "%.3g MB", bytes / 1048576.0);
  return buf;
}

void checkMemoryBudget(double bytes, const std::string& where, const std::string& what) {
  const double limit = static_cast<double>(memoryBudgetBytes());
  if (!(bytes <= limit))
    throw InputError(where + ": " + what + " needs " + formatBytes(bytes) + ", above the memory budget of " + formatBytes(limit) +
                     " (lower the value, or raise the budget with --max-memory GB or CANDELA_MAX_MEMORY_GB)");
}

int jsonNestingDepth(const std::string& text, int limit) {
  int depth = 0, deepest = 0;
  bool inString = false, escaped = false;
  for (const char c : text) {
    if (inString) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        inString = false;
      continue;
    }
    if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > limit) return deepest;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

bool isValidUtf8(const std::string& s) {
  size_t i = 0;
  const size_t n = s.size();
  while (i < n) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    int extra;
    unsigned int cp;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      extra = 1, cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      extra = 2, cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      extra = 3, cp = c & 0x07;
    } else {
      return false;
    }
    if (i + static_cast<size_t>(extra) >= n) return false;
    for (int k = 1; k <= extra; ++k) {
      const unsigned char cc = static_cast<unsigned char>(s[i + static_cast<size_t>(k)]);
      if ((cc & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (cc & 0x3F);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are invalid.
    if ((extra == 1 && cp < 0x80) || (extra == 2 && cp < 0x800) || (extra == 3 && cp < 0x10000) || cp > 0x10FFFF ||
        (cp >= 0xD800 && cp <= 0xDFFF))
      return false;
    i += static_cast<size_t>(extra) + 1;
  }
  return true;
}

}  // namespace candela
