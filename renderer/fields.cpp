#include "fields.h"

#include "input_limits.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace candela {

namespace {
std::string shortDump(const Json* j) {
  if (!j) return "nothing";
  // Containers are summarised, not dumped: a huge value must not make a huge message.
  if (j->is_array() && j->size() > 8) return "an array of " + std::to_string(j->size()) + " elements";
  if (j->is_object() && j->size() > 8) return "an object of " + std::to_string(j->size()) + " fields";
  std::string s = j->dump(-1, ' ', false, Json::error_handler_t::replace);
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}
std::string rangeText(Range r) {
  std::ostringstream os;
  if (r.min > -1e29 && r.max < 1e29)
    os << " in [" << r.min << ", " << r.max << "]";
  else if (r.min > -1e29)
    os << (r.min == 0.0 ? " >= 0" : r.min <= 1e-29 ? " > 0" : " >= " + std::to_string(r.min));
  else if (r.max < 1e29)
    os << " <= " << r.max;
  return os.str();
}
}  // namespace

std::string shortJson(const Json& value) { return shortDump(&value); }

JsonReader::JsonReader(const Json& object, std::string file, std::string path)
    : object_(object), file_(std::move(file)), path_(std::move(path)) {}

void JsonReader::fail(const std::string& key, const std::string& expected, const Json* got) const {
  throw InputError(file_ + ": " + pathOf(key) + ": expected " + expected + ", got " + shortDump(got));
}

const Json* JsonReader::take(const char* key, bool isRequired) {
  claimed_.emplace_back(key);
  auto it = object_.find(key);
  if (it == object_.end()) {
    if (isRequired) throw InputError(file_ + ": " + pathOf(key) + ": required field is missing");
    return nullptr;
  }
  return &*it;
}

JsonReader JsonReader::child(const Json& j, const char* key, const char* expected) {
  if (!j.is_object()) fail(key, expected, &j);
  return JsonReader(j, file_, pathOf(key));
}

void JsonReader::finish() const {
  for (auto it = object_.begin(); it != object_.end(); ++it) {
    if (std::find(claimed_.begin(), claimed_.end(), it.key()) == claimed_.end()) {
      std::string known;
      for (const auto& k : claimed_) known += (known.empty() ? "" : ", ") + k;
      throw InputError(file_ + ": " + pathOf(it.key()) + ": unknown field (expected one of: " + known + ")");
    }
  }
}

void JsonReader::read(const char* key, bool& v, Range, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  if (!j->is_boolean()) fail(key, "true or false", j);
  v = j->get<bool>();
}

void JsonReader::read(const char* key, int& v, Range r, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  if (!j->is_number_integer() || j->get<double>() < r.min || j->get<double>() > r.max)
    fail(key, "an integer" + rangeText(r), j);
  v = j->get<int>();
}

void JsonReader::read(const char* key, uint32_t& v, Range r, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  if (!j->is_number_integer() || j->get<double>() < std::max(0.0, r.min) || j->get<double>() > std::min(4294967295.0, r.max))
    fail(key, "a non-negative integer" + rangeText(r), j);
  v = j->get<uint32_t>();
}

void JsonReader::read(const char* key, float& v, Range r, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  // Compared as float: a UI slider at its bound writes the float nearest the bound (0.99f is
  // 0.99000001 as a double), which must read back as in range.
  if (!j->is_number() || !std::isfinite(j->get<double>()) || std::abs(j->get<double>()) > 3.0e38 ||
      j->get<float>() < static_cast<float>(r.min) || j->get<float>() > static_cast<float>(r.max))
    fail(key, "a number" + rangeText(r), j);
  v = j->get<float>();
}

void JsonReader::read(const char* key, std::string& v, Range, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  if (!j->is_string()) fail(key, "a string", j);
  v = j->get<std::string>();
}

void JsonReader::read(const char* key, Vec3& v, Range r, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  auto ok = [&](const Json& e) {
    return e.is_number() && std::isfinite(e.get<double>()) && std::abs(e.get<double>()) <= 3.0e38 &&
           e.get<float>() >= static_cast<float>(r.min) && e.get<float>() <= static_cast<float>(r.max);
  };
  if (j->is_array() && j->size() == 3 && ok((*j)[0]) && ok((*j)[1]) && ok((*j)[2])) {
    v = Vec3((*j)[0].get<float>(), (*j)[1].get<float>(), (*j)[2].get<float>());
    return;
  }
  fail(key, "an array of 3 numbers" + rangeText(r), j);
}

void JsonReader::read(const char* key, std::pair<int, int>& v, Range r, bool req) {
  const Json* j = take(key, req);
  if (!j) return;
  auto ok = [&](const Json& e) { return e.is_number_integer() && e.get<double>() >= r.min && e.get<double>() <= r.max; };
  if (j->is_array() && j->size() == 2 && ok((*j)[0]) && ok((*j)[1])) {
    v = {(*j)[0].get<int>(), (*j)[1].get<int>()};
    return;
  }
  fail(key, "an array of 2 integers" + rangeText(r), j);
}

void applySetting(Json& doc, const std::string& assignment, const std::string& origin) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(origin + ": '" + assignment + "': expected key=value, such as strategy.majorant.cell_size=16");
  const std::string key = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  if (jsonNestingDepth(text, limits::kMaxJsonDepth) > limits::kMaxJsonDepth)
    throw InputError(origin + ": " + key + ": the value nests deeper than " + std::to_string(limits::kMaxJsonDepth) + " levels");
  Json value = Json::parse(text, nullptr, false);
  if (value.is_discarded()) {
    // Not JSON (a bare word, or a number past double such as 1e309): taken as a string, which
    // must be UTF-8 to be written back to JSON and image metadata.
    if (!isValidUtf8(text)) throw InputError(origin + ": " + key + ": expected valid UTF-8 text");
    value = text;
  }

  Json* node = &doc;
  std::string walked;
  std::stringstream parts(key);
  std::string part;
  std::vector<std::string> names;
  while (std::getline(parts, part, '.')) names.push_back(part);
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    walked += (walked.empty() ? "" : ".") + name;
    const bool last = i + 1 == names.size();
    if (node->is_array()) {
      char* end = nullptr;
      const long index = std::strtol(name.c_str(), &end, 10);
      if (*end != '\0' || index < 0 || static_cast<size_t>(index) >= node->size())
        throw InputError(origin + ": " + walked + ": expected an index below " + std::to_string(node->size()));
      node = &(*node)[static_cast<size_t>(index)];
    } else {
      if (node->is_null()) *node = Json::object();
      if (!node->is_object()) throw InputError(origin + ": " + walked + ": cannot set a field inside a " + node->type_name());
      node = &(*node)[name];
    }
    if (last) *node = value;
  }
}

}  // namespace candela
