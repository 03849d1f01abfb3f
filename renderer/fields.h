// Reflection for plain parameter structs. Each struct lists its fields once, in a template
// `visit(Visitor&)`; visitors turn that list into JSON reading (with errors that name the file, the
// field and what was expected), JSON writing, and (in the viewer) UI widgets with tooltips.
#pragma once

#include "core.h"

#include <nlohmann/json.hpp>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace candela {

using Json = nlohmann::json;

// A bad scene, settings file or parameter. The message always reads "FILE: FIELD: expected ..., got ...".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Numeric limits of a field, inclusive. Also carries the UI hint for sliders.
struct Range {
  double min = -1e30;
  double max = 1e30;
};
inline constexpr Range kNonNegative{0.0, 1e30};
inline constexpr Range kPositive{1e-30, 1e30};
inline constexpr Range kUnit{0.0, 1.0};

// Enumerations declare their spellings by specialising this.
template <class E>
struct EnumNames;  // static const std::vector<std::pair<E, const char*>>& get();

template <class E>
const char* enumName(E value) {
  for (const auto& [v, name] : EnumNames<E>::get())
    if (v == value) return name;
  return "?";
}

// Reads a struct from a JSON object. Unknown keys are errors; a field marked required must be
// present; others keep their current (default) value.
class JsonReader {
 public:
  JsonReader(const Json& object, std::string file, std::string path);

  template <class T>
  void field(const char* key, T& value, const char* /*doc*/, Range range = {}) {
    read(key, value, range, false);
  }
  template <class T>
  void required(const char* key, T& value, const char* /*doc*/, Range range = {}) {
    read(key, value, range, true);
  }
  // Nested struct with its own visit().
  template <class S>
  void object(const char* key, S& value, const char* /*doc*/) {
    const Json* j = take(key, false);
    if (!j) return;
    JsonReader sub = child(*j, key, "an object");
    value.visit(sub);
    sub.finish();
  }
  // Fields the reader should read before visiting (such as a "type" that selects the others).
  bool has(const char* key) const { return object_.contains(key); }
  const std::string& file() const { return file_; }
  std::string pathOf(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[noreturn]] void fail(const std::string& key, const std::string& expected, const Json* got) const;
  // Throws for keys no field claimed.
  void finish() const;
  static constexpr bool kReading = true;
  static constexpr bool kWriting = false;

 private:
  const Json* take(const char* key, bool isRequired);
  JsonReader child(const Json& j, const char* key, const char* expected);
  void read(const char* key, bool& v, Range, bool req);
  void read(const char* key, int& v, Range r, bool req);
  void read(const char* key, uint32_t& v, Range r, bool req);
  void read(const char* key, float& v, Range r, bool req);
  void read(const char* key, std::string& v, Range, bool req);
  void read(const char* key, Vec3& v, Range r, bool req);
  void read(const char* key, std::pair<int, int>& v, Range r, bool req);
  template <class E, class = decltype(EnumNames<E>::get())>
  void read(const char* key, E& v, Range, bool req) {
    const Json* j = take(key, req);
    if (!j) return;
    std::string expected = "one of";
    for (const auto& [e, name] : EnumNames<E>::get()) {
      expected += std::string(" \"") + name + "\"";
      if (j->is_string() && j->get<std::string>() == name) {
        v = e;
        return;
      }
    }
    fail(key, expected, j);
  }

  const Json& object_;
  std::string file_;
  std::string path_;
  std::vector<std::string> claimed_;
};

// Writes every field of a struct to a JSON object.
class JsonWriter {
 public:
  explicit JsonWriter(Json& out) : out_(out) {}
  template <class T>
  void field(const char* key, const T& value, const char*, Range = {}) {
    out_[key] = toJson(value);
  }
  template <class T>
  void required(const char* key, const T& value, const char* doc, Range r = {}) {
    field(key, value, doc, r);
  }
  template <class S>
  void object(const char* key, const S& value, const char*) {
    Json sub = Json::object();
    JsonWriter w(sub);
    const_cast<S&>(value).visit(w);
    out_[key] = sub;
  }
  bool has(const char*) const { return true; }
  static constexpr bool kReading = false;
  static constexpr bool kWriting = true;

 private:
  static Json toJson(bool v) { return v; }
  static Json toJson(int v) { return v; }
  static Json toJson(uint32_t v) { return v; }
  static Json toJson(float v) { return v; }
  static Json toJson(const std::string& v) { return v; }
  static Json toJson(const Vec3& v) { return Json::array({v.x, v.y, v.z}); }
  static Json toJson(const std::pair<int, int>& v) { return Json::array({v.first, v.second}); }
  template <class E, class = decltype(EnumNames<E>::get())>
  static Json toJson(E v) {
    return enumName(v);
  }
  Json& out_;
};

template <class S>
Json toJson(const S& s) {
  Json j = Json::object();
  JsonWriter w(j);
  const_cast<S&>(s).visit(w);
  return j;
}

// A value for an error message: at most about 60 characters, large containers summarised.
std::string shortJson(const Json& value);

// Reads a struct whose current values are the defaults; `file` and `path` name the source in errors.
template <class S>
void fromJson(const Json& j, S& s, const std::string& file, const std::string& path) {
  if (!j.is_object()) throw InputError(file + ": " + (path.empty() ? "(top level)" : path) + ": expected an object, got " + shortJson(j));
  JsonReader r(j, file, path);
  s.visit(r);
  r.finish();
}

// Applies `key=value` edits (dotted JSON paths, array indices as numbers) to a JSON document.
// The value is parsed as JSON when it is valid JSON, else taken as a string.
void applySetting(Json& doc, const std::string& assignment, const std::string& origin);

}  // namespace candela
