#pragma once
// One table of fields per section of an input file: each entry names its key, type, default,
// allowed range and meaning once, and from the table come the reader (read_fields), the writer of
// the resolved file (write_fields), the JSON Schema (schema_of) and the rows of the reference
// tables in docs/ (doc_rows). scene_fields.cpp holds the scene's tables, element_test_json.cpp the
// element test's; docs/architecture.md "How to add a scene key" is the recipe.
#include "json_fields.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace talus::scene_detail {

constexpr double kHuge = 1e30;  // "no bound": ranges with this end are open-ended in docs and schema

/// A closed or open interval; kHuge at an end means unbounded (docs write "≥ 0", "finite").
struct Range {
  double lo = -kHuge, hi = kHuge;
  bool open_lo = false, open_hi = false;
  static Range any() { return {}; }
};

/// What the docs and the schema need of a key.
struct FieldInfo {
  std::string key;      // the key in its object; empty for a check that reads no key
  std::string doc_key;  // the key as the docs name it, when one row stands for several ("<face>")
  std::string type;     // docs "type" column
  std::string fallback; // docs "default" column ("required" for a required key)
  std::string allowed;  // docs "allowed" column
  std::string doc;      // docs "meaning" column; also the schema's description
  Json schema;          // the JSON Schema of the value
  bool required = false;
  bool row = true;      // a docs row of its own (sections like "grid" have only their members' rows)
  /// For a table with a selector (materials: "model"; element-test paths: "type"): the selector
  /// values under which this key exists; empty = always.
  std::vector<std::string> when;
  /// Rows of the members of an object-valued key, relative to it (docs only).
  std::vector<std::vector<std::string>> member_rows;
};

/// Optional settings of a field, given by name: {.unit = "s", .required = true}.
struct FieldOptions {
  std::string unit;            // docs type column: "number [s]"
  bool required = false;
  std::string type;            // override the docs type column
  std::string fallback;        // override the docs default column
  std::string allowed;         // override the docs allowed column
  /// The range is checked by the layer that owns the value (e.g. the DruckerPrager constructor,
  /// whose message names the key); the reader takes any finite number. Docs and schema still
  /// show the range.
  bool domain_checked = false;
  std::vector<std::string> when;
};

template <class S>
struct Field {
  FieldInfo info;
  std::function<void(ObjectReader&, S&)> read;
  std::function<void(const S&, Json&)> write;  // adds info.key to the object (or leaves it out)
};

template <class S>
using Fields = std::vector<Field<S>>;

/// A table and, when some keys depend on another key's value, that selector key.
template <class S>
struct Table {
  Fields<S> fields;
  std::string selector;             // e.g. "model"; empty = none
  std::vector<std::string> values;  // the selector's values, the default first
  std::function<std::string(const S&)> selected;  // the selector's value of a read object
};

// ---- formatting for docs ------------------------------------------------------------------------

inline std::string number_text(double v) { return fmt::format("{}", v); }

inline std::string range_text(const Range& r) {
  const bool lo = r.lo > -kHuge, hi = r.hi < kHuge;
  if (lo && hi)
    return fmt::format("{}{}, {}{}", r.open_lo ? "(" : "[", number_text(r.lo), number_text(r.hi), r.open_hi ? ")" : "]");
  if (lo) return fmt::format("{} {}", r.open_lo ? ">" : "≥", number_text(r.lo));
  if (hi) return fmt::format("{} {}", r.open_hi ? "<" : "≤", number_text(r.hi));
  return "finite";
}

inline void add_range(Json& schema, const Range& r) {
  // (an unbounded end is the reader's 1e30, which it refuses past: the schema said young = 1e31 was valid)
  schema[r.open_lo && r.lo > -kHuge ? "exclusiveMinimum" : "minimum"] = std::max(r.lo, -kHuge);
  schema[r.open_hi && r.hi < kHuge ? "exclusiveMaximum" : "maximum"] = std::min(r.hi, kHuge);
}

inline std::string choices_text(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "`" : ", `") + n + "`";
  return text;
}

inline FieldInfo make_info(std::string key, std::string type, std::string fallback, std::string allowed, std::string doc,
                           Json schema, const FieldOptions& o) {
  FieldInfo info;
  info.key = std::move(key);
  info.type = !o.type.empty() ? o.type : o.unit.empty() ? type : type + " [" + o.unit + "]";
  info.required = o.required;
  info.fallback = !o.fallback.empty() ? o.fallback : o.required ? "required" : fallback;
  info.allowed = !o.allowed.empty() ? o.allowed : allowed;
  info.doc = std::move(doc);
  schema["description"] = info.doc;
  info.schema = std::move(schema);
  info.when = o.when;
  return info;
}

// ---- field factories; `at` is a generic lambda giving the value's place in S --------------------
// (a default-constructed S holds the default of every optional key)

template <class S, class At>
Field<S> number(std::string key, At at, Range range, std::string doc, FieldOptions o = {}) {
  S blank{};
  const double fallback = at(blank);
  Json schema = {{"type", "number"}};
  add_range(schema, range);
  if (!o.required) schema["default"] = fallback;
  Field<S> f{make_info(key, "number", number_text(fallback), range_text(range), std::move(doc), schema, o), {}, {}};
  f.read = [key, at, range, domain_checked = o.domain_checked, required = o.required](ObjectReader& r, S& s) {
    double& v = at(s);
    const auto read = [&](const Range& within) {
      v = required ? r.number(key, within.lo, within.hi, within.open_lo, within.open_hi)
                   : r.number_or(key, v, within.lo, within.hi, within.open_lo, within.open_hi);
    };
    if (!domain_checked) return read(range);
    try {
      read(Range::any());
    } catch (const Error& e) {
      // No number, or one past 1e30: refused here, but with the key's own range (friction_angle =
      // 1e31 was "outside [-1e+30, 1e+30]", though only (0, 90) is allowed). Inside any(), the
      // owning layer checks it.
      if (e.kind() != Error::Kind::Input) throw;
      read(range);
      throw;
    }
  };
  f.write = [key, at](const S& s, Json& j) { j[key] = at(s); };
  return f;
}

template <class S, class At>
Field<S> integer(std::string key, At at, int lo, int hi, std::string doc, FieldOptions o = {}) {
  S blank{};
  const int fallback = at(blank);
  Json schema = {{"type", "integer"}, {"minimum", lo}, {"maximum", hi}};
  if (!o.required) schema["default"] = fallback;
  Field<S> f{make_info(key, "integer", std::to_string(fallback), fmt::format("[{}, {}]", lo, hi), std::move(doc), schema, o),
             {}, {}};
  f.read = [key, at, lo, hi, required = o.required](ObjectReader& r, S& s) {
    int& v = at(s);
    v = required ? r.integer(key, lo, hi) : r.integer_or(key, v, lo, hi);
  };
  f.write = [key, at](const S& s, Json& j) { j[key] = at(s); };
  return f;
}

template <class S, class At>
Field<S> boolean(std::string key, At at, std::string doc, FieldOptions o = {}) {
  S blank{};
  const bool fallback = at(blank);
  Json schema = {{"type", "boolean"}, {"default", fallback}};
  Field<S> f{make_info(key, "boolean", fallback ? "true" : "false", "", std::move(doc), schema, o), {}, {}};
  f.read = [key, at](ObjectReader& r, S& s) {
    bool& v = at(s);
    v = r.boolean_or(key, v);
  };
  f.write = [key, at](const S& s, Json& j) { j[key] = at(s); };
  return f;
}

template <class S, class At>
Field<S> string(std::string key, At at, std::string doc, FieldOptions o = {}) {
  S blank{};
  const std::string fallback = at(blank);
  Json schema = {{"type", "string"}};
  if (!o.required) schema["default"] = fallback;
  Field<S> f{make_info(key, "string", "`\"" + fallback + "\"`", "", std::move(doc), schema, o), {}, {}};
  f.read = [key, at, required = o.required](ObjectReader& r, S& s) {
    std::string& v = at(s);
    v = required ? r.string(key) : r.string_or(key, v);
  };
  f.write = [key, at](const S& s, Json& j) { j[key] = at(s); };
  return f;
}

/// One of a fixed set of words, each naming a value of an enum (or any type with ==).
template <class S, class At, class E>
Field<S> choice(std::string key, At at, std::vector<std::pair<std::string, E>> names, std::string doc, FieldOptions o = {}) {
  S blank{};
  const E fallback = at(blank);
  std::vector<std::string> words;
  std::string fallback_word;
  for (const auto& [word, value] : names) {
    words.push_back(word);
    if (value == fallback) fallback_word = word;
  }
  Json schema = {{"type", "string"}, {"enum", words}};
  if (!o.required) schema["default"] = fallback_word;
  Field<S> f{make_info(key, "string", "`\"" + fallback_word + "\"`", choices_text(words), std::move(doc), schema, o), {},
             {}};
  f.read = [key, at, names, words, required = o.required](ObjectReader& r, S& s) {
    E& v = at(s);
    std::string current;
    for (const auto& [word, value] : names)
      if (value == v) current = word;
    const std::string word = r.choice(key, required ? std::string() : current, words);
    for (const auto& [w, value] : names)
      if (w == word) v = value;
  };
  f.write = [key, at, names](const S& s, Json& j) {
    for (const auto& [word, value] : names)
      if (value == at(s)) j[key] = word;
  };
  return f;
}

/// Three numbers; `range` applies to each (by default: finite, below 1e30 in magnitude like every
/// number, so that gravity = [0, 0, -1e308] is refused rather than flinging the particles at step 0).
template <class S, class At>
Field<S> vec3(std::string key, At at, std::string doc, FieldOptions o = {}, Range range = {-kHuge, kHuge}) {
  S blank{};
  const Vec3 fallback = at(blank);
  Json item = {{"type", "number"}};
  add_range(item, range);
  Json schema = {{"type", "array"}, {"items", item}, {"minItems", 3}, {"maxItems", 3}};
  if (!o.required) schema["default"] = Json::array({fallback[0], fallback[1], fallback[2]});
  Field<S> f{make_info(key, "[x, y, z]",
                       fmt::format("[{}, {}, {}]", number_text(fallback[0]), number_text(fallback[1]), number_text(fallback[2])),
                       range_text(range), std::move(doc), schema, o),
             {}, {}};
  f.read = [key, at, range, required = o.required](ObjectReader& r, S& s) {
    Vec3& v = at(s);
    if (required || r.has(key)) v = r.vec3(key, range.lo, range.hi);
  };
  f.write = [key, at](const S& s, Json& j) {
    const Vec3& v = at(s);
    j[key] = Json::array({v[0], v[1], v[2]});
  };
  return f;
}

/// A key read and written by hand (arrays of points, names resolved later, ...): the table still
/// gives its docs row and schema.
template <class S>
Field<S> custom(std::string key, std::string type, std::string fallback, std::string allowed, std::string doc, Json schema,
                std::function<void(ObjectReader&, S&)> read, std::function<void(const S&, Json&)> write,
                FieldOptions o = {}) {
  return Field<S>{make_info(std::move(key), std::move(type), std::move(fallback), std::move(allowed), std::move(doc),
                            std::move(schema), o),
                  std::move(read), std::move(write)};
}

/// A step of the reader that reads no key of its own: a check across keys, run in table order.
template <class S>
Field<S> check(std::function<void(ObjectReader&, S&)> step, std::vector<std::string> when = {}) {
  Field<S> f;
  f.info.row = false;
  f.info.when = std::move(when);
  f.read = std::move(step);
  f.write = [](const S&, Json&) {};
  return f;
}

/// The fields of a member (e.g. DruckerPragerParameters inside MaterialSpec) as fields of S.
template <class S, class M, class At>
Fields<S> lift(const Fields<M>& member, At at, std::vector<std::string> when = {}) {
  Fields<S> out;
  for (const Field<M>& f : member) {
    Field<S> g;
    g.info = f.info;
    if (!when.empty()) g.info.when = when;
    g.read = [read = f.read, at](ObjectReader& r, S& s) { read(r, at(s)); };
    g.write = [write = f.write, at](const S& s, Json& j) { write(at(s), j); };
    out.push_back(std::move(g));
  }
  return out;
}

template <class S>
Fields<S> join(std::initializer_list<Fields<S>> parts) {
  Fields<S> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// ---- what the table gives ----------------------------------------------------------------------

template <class S>
bool applies(const FieldInfo& info, const std::string& selected) {
  if (info.when.empty()) return true;
  for (const auto& w : info.when)
    if (w == selected) return true;
  return false;
}

/// Reads every field of the table in order, then refuses keys the table does not name.
template <class S>
void read_fields(ObjectReader& r, S& s, const Table<S>& t) {
  // Unknown keys first, once the selector (which decides the keys) is known.
  const auto refuse_unknown = [&] {
    std::vector<std::string> allowed;
    for (const Field<S>& f : t.fields)
      if (!f.info.key.empty() && (t.selector.empty() || applies<S>(f.info, t.selected(s))) &&
          std::find(allowed.begin(), allowed.end(), f.info.key) == allowed.end())
        allowed.push_back(f.info.key);
    r.refuse_unknown(allowed);
  };
  if (t.selector.empty()) refuse_unknown();
  for (const Field<S>& f : t.fields) {
    if (!t.selector.empty() && !f.info.when.empty() && !applies<S>(f.info, t.selected(s))) continue;
    f.read(r, s);
    if (!t.selector.empty() && f.info.key == t.selector) refuse_unknown();
  }
  r.finish();
}

template <class S>
Json write_fields(const S& s, const Table<S>& t) {
  Json j = Json::object();
  for (const Field<S>& f : t.fields) {
    if (!t.selector.empty() && !f.info.when.empty() && !applies<S>(f.info, t.selected(s))) continue;
    f.write(s, j);
  }
  return j;
}

/// The JSON Schema of an object read by the table. With a selector, each value gets its own
/// branch: its keys, their ranges, and no others (draft-07: if/then with propertyNames).
template <class S>
Json schema_of(const Table<S>& t, const std::string& description = "") {
  Json schema = {{"type", "object"}};
  if (!description.empty()) schema["description"] = description;
  auto branch = [&](const std::string& value, Json& properties, Json& required, std::vector<std::string>& names) {
    for (const Field<S>& f : t.fields) {
      if (f.info.key.empty() || (!value.empty() && !applies<S>(f.info, value))) continue;
      if (!properties.contains(f.info.key)) names.push_back(f.info.key);
      properties[f.info.key] = f.info.schema;
      if (f.info.required) required.push_back(f.info.key);
    }
  };
  if (t.selector.empty()) {
    Json properties = Json::object(), required = Json::array();
    std::vector<std::string> names;
    branch("", properties, required, names);
    schema["properties"] = properties;
    if (!required.empty()) schema["required"] = required;
    schema["additionalProperties"] = false;
    return schema;
  }
  Json all = Json::array();
  Json any_properties = Json::object();
  for (std::size_t i = 0; i < t.values.size(); ++i) {
    const std::string& value = t.values[i];
    Json properties = Json::object(), required = Json::array();
    std::vector<std::string> names;
    branch(value, properties, required, names);
    for (const auto& n : names) any_properties[n] = true;
    Json when = {{"properties", {{t.selector, {{"const", value}}}}}};
    if (i > 0) when["required"] = Json::array({t.selector});  // the first value is the default
    Json then = {{"properties", properties}, {"propertyNames", {{"enum", names}}}};
    if (!required.empty()) then["required"] = required;
    all.push_back({{"if", when}, {"then", then}});
  }
  schema["properties"] = any_properties;
  for (const Field<S>& f : t.fields)
    if (f.info.key == t.selector) schema["properties"][t.selector] = f.info.schema;
  schema["allOf"] = all;
  return schema;
}

/// Docs rows (key path, type, default, allowed, meaning) under `prefix`.
template <class S>
std::vector<std::vector<std::string>> doc_rows(const Table<S>& t, const std::string& prefix) {
  std::vector<std::vector<std::string>> rows;
  for (const Field<S>& f : t.fields) {
    if (f.info.key.empty()) continue;
    const std::string& key = f.info.doc_key.empty() ? f.info.key : f.info.doc_key;
    const std::string path = prefix.empty() ? key : prefix + "." + key;
    std::string meaning = f.info.doc;
    if (!t.selector.empty() && !f.info.when.empty()) {
      std::string list;
      for (const auto& w : f.info.when) list += (list.empty() ? "" : ", ") + w;
      meaning = "(" + t.selector + " " + list + ") " + meaning;
    }
    if (f.info.row) rows.push_back({path, f.info.type, f.info.fallback, f.info.allowed, meaning});
    for (auto row : f.info.member_rows) {
      row[0] = path + (row[0][0] == '[' ? "" : ".") + row[0];  // bodies[i].name, grid.terrain.points
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

/// An object-valued key whose members another table reads (a different type M: the element
/// test's material); `read` and `write` say when it is present.
template <class S, class M>
Field<S> custom_object(std::string key, const Table<M>& members, std::string fallback, std::string doc,
                       std::function<void(ObjectReader&, S&)> read, std::function<void(const S&, Json&)> write,
                       FieldOptions o = {}) {
  Field<S> f = custom<S>(std::move(key), "object", std::move(fallback), "", doc, schema_of(members, doc), std::move(read),
                         std::move(write), o);
  f.info.member_rows = doc_rows(members, "");
  return f;
}

/// A table built once (with its schema and docs rows), however often it is read.
template <class S, Table<S> (*make)()>
const Table<S>& table_of() {
  static const Table<S> table = make();
  return table;
}

template <class S>
struct ObjectHooks {
  std::function<void(S&)> begin;               // before the members are read (e.g. "present = on")
  std::function<void(ObjectReader&, S&)> end;  // after them: checks across the members
  std::function<bool(const S&)> present;       // whether the writer includes the key (null: when it has members)
};

/// An object-valued key whose members the table `members` reads into the same S, when the key is
/// there (always, with .required); its schema and docs rows are that table's.
template <class S>
Field<S> object(std::string key, const Table<S>& (*members)(), std::string fallback, std::string doc,
                ObjectHooks<S> hooks = {}, FieldOptions o = {}, bool row = true) {
  const bool required = o.required;
  Field<S> f = custom<S>(
      key, "object", std::move(fallback), "", doc, schema_of(members(), doc),
      [key, members, hooks, required](ObjectReader& r, S& s) {
        if (!required && !r.has(key)) return;
        if (hooks.begin) hooks.begin(s);
        ObjectReader inner = r.object(key);
        read_fields(inner, s, members());
        if (hooks.end) hooks.end(inner, s);
      },
      [key, members, hooks](const S& s, Json& j) {
        if (hooks.present && !hooks.present(s)) return;
        Json inner = write_fields(s, members());
        if (hooks.present || !inner.empty()) j[key] = std::move(inner);
      },
      o);
  f.info.row = row;
  f.info.member_rows = doc_rows(members(), "");
  return f;
}

}  // namespace talus::scene_detail
