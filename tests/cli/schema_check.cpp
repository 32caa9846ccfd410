// schema_check: checks a JSON document against a JSON Schema (draft 2020-12), for the subset of
// keywords that spec/inspect-schema.json and spec/scene-schema.json use. A keyword outside that
// subset is an error, so the schema cannot grow past what this checker enforces.
//
//   vff_cli_schema_check SCHEMA.json INSTANCE.json    (INSTANCE "-" reads stdin)
//   exit 0: conforms; 1: does not (every violation printed); 2: bad arguments, files or schema.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>

using nlohmann::json;

namespace {

const std::set<std::string> kSupported = {"$schema", "$id",      "title",      "description", "$defs",
                                          "$ref",    "type",     "properties", "required",    "additionalProperties",
                                          "items",   "minItems", "maxItems",   "enum",        "const",
                                          "minimum", "maximum",  "anyOf",      "pattern",
                                          "exclusiveMinimum"};

struct SchemaError {
  std::string what;
};

class Checker {
 public:
  explicit Checker(json root) : root_(std::move(root)) {}

  // Appends "path: problem" lines to `errors`.
  void check(const json& schema, const json& v, const std::string& path, std::vector<std::string>& errors) const {
    if (schema.is_boolean()) {
      if (!schema.get<bool>()) errors.push_back(path + ": not allowed");
      return;
    }
    if (!schema.is_object()) throw SchemaError{"schema at " + path + " is not an object"};
    for (const auto& [key, _] : schema.items())
      if (!kSupported.count(key)) throw SchemaError{"unsupported keyword '" + key + "' (at " + path + ")"};

    if (schema.contains("$ref")) check(resolve(schema["$ref"].get<std::string>()), v, path, errors);
    if (schema.contains("type")) {
      const json& t = schema["type"];
      bool ok = false;
      if (t.is_string()) ok = isType(v, t.get<std::string>());
      for (const json& one : t.is_array() ? t : json::array()) ok = ok || isType(v, one.get<std::string>());
      if (!ok) errors.push_back(path + ": expected type " + t.dump() + ", got " + v.type_name());
    }
    if (schema.contains("enum")) {
      bool ok = false;
      for (const json& e : schema["enum"]) ok = ok || e == v;
      if (!ok) errors.push_back(path + ": " + v.dump() + " is not one of " + schema["enum"].dump());
    }
    if (schema.contains("const") && schema["const"] != v)
      errors.push_back(path + ": expected " + schema["const"].dump() + ", got " + v.dump());
    if (v.is_number()) {
      if (schema.contains("minimum") && v.get<double>() < schema["minimum"].get<double>())
        errors.push_back(path + ": " + v.dump() + " < minimum " + schema["minimum"].dump());
      if (schema.contains("exclusiveMinimum") && v.get<double>() <= schema["exclusiveMinimum"].get<double>())
        errors.push_back(path + ": " + v.dump() + " <= exclusiveMinimum " + schema["exclusiveMinimum"].dump());
      if (schema.contains("maximum") && v.get<double>() > schema["maximum"].get<double>())
        errors.push_back(path + ": " + v.dump() + " > maximum " + schema["maximum"].dump());
    }
    if (v.is_string() && schema.contains("pattern")) {
      const std::regex re(schema["pattern"].get<std::string>(), std::regex::ECMAScript);
      if (!std::regex_search(v.get<std::string>(), re))
        errors.push_back(path + ": " + v.dump() + " does not match " + schema["pattern"].dump());
    }
    if (schema.contains("anyOf")) {
      bool ok = false;
      for (const json& sub : schema["anyOf"]) {
        std::vector<std::string> subErrors;
        check(sub, v, path, subErrors);
        ok = ok || subErrors.empty();
      }
      if (!ok) errors.push_back(path + ": matches none of anyOf");
    }
    if (v.is_object()) {
      for (const json& r : schema.value("required", json::array()))
        if (!v.contains(r.get<std::string>()))
          errors.push_back(path + ": required key '" + r.get<std::string>() + "' missing");
      const json props = schema.value("properties", json::object());
      for (const auto& [key, value] : v.items()) {
        const std::string sub = path + "/" + key;
        if (props.contains(key))
          check(props[key], value, sub, errors);
        else if (schema.contains("additionalProperties"))
          check(schema["additionalProperties"], value, sub, errors);
      }
    }
    if (v.is_array()) {
      if (schema.contains("minItems") && v.size() < schema["minItems"].get<size_t>())
        errors.push_back(path + ": fewer than " + schema["minItems"].dump() + " items");
      if (schema.contains("maxItems") && v.size() > schema["maxItems"].get<size_t>())
        errors.push_back(path + ": more than " + schema["maxItems"].dump() + " items");
      if (schema.contains("items"))
        for (size_t i = 0; i < v.size(); ++i) check(schema["items"], v[i], path + "/" + std::to_string(i), errors);
    }
  }

  // Walks the whole schema once, so that an unsupported keyword is caught even where no instance
  // reaches it.
  static void lint(const json& schema, const std::string& path) {
    if (schema.is_boolean()) return;
    if (!schema.is_object()) throw SchemaError{"schema at " + path + " is not an object"};
    for (const auto& [key, sub] : schema.items()) {
      if (!kSupported.count(key)) throw SchemaError{"unsupported keyword '" + key + "' (at " + path + ")"};
      if (key == "$defs" || key == "properties")
        for (const auto& [name, s] : sub.items()) lint(s, path + "/" + key + "/" + name);
      if (key == "additionalProperties" || key == "items") lint(sub, path + "/" + key);
      if (key == "anyOf")
        for (size_t i = 0; i < sub.size(); ++i) lint(sub[i], path + "/anyOf/" + std::to_string(i));
      if (key == "type")
        for (const json& t : sub.is_array() ? sub : json::array({sub})) isType(json(), t.get<std::string>());
    }
  }

 private:
  static bool isType(const json& v, const std::string& t) {
    if (t == "object") return v.is_object();
    if (t == "array") return v.is_array();
    if (t == "string") return v.is_string();
    if (t == "boolean") return v.is_boolean();
    if (t == "null") return v.is_null();
    if (t == "number") return v.is_number();
    if (t == "integer") return v.is_number_integer();
    throw SchemaError{"unknown type '" + t + "'"};
  }

  const json& resolve(const std::string& ref) const {
    const std::string prefix = "#/$defs/";
    if (ref.rfind(prefix, 0) != 0) throw SchemaError{"only local #/$defs/ references are supported: " + ref};
    const std::string name = ref.substr(prefix.size());
    if (!root_.contains("$defs") || !root_["$defs"].contains(name)) throw SchemaError{"unresolved reference " + ref};
    return root_["$defs"][name];
  }

  json root_;
};

bool load(const std::string& path, json& out) {
  std::stringstream ss;
  if (path == "-") {
    ss << std::cin.rdbuf();
  } else {
    std::ifstream in(path);
    if (!in) {
      std::fprintf(stderr, "schema_check: cannot open %s\n", path.c_str());
      return false;
    }
    ss << in.rdbuf();
  }
  out = json::parse(ss.str(), nullptr, false);
  if (out.is_discarded()) {
    std::fprintf(stderr, "schema_check: %s is not valid JSON\n", path.c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: vff_cli_schema_check SCHEMA.json INSTANCE.json|-\n");
    return 2;
  }
  json schema, instance;
  if (!load(argv[1], schema) || !load(argv[2], instance)) return 2;
  if (schema.value("$schema", "") != "https://json-schema.org/draft/2020-12/schema") {
    std::fprintf(stderr, "schema_check: the schema does not declare draft 2020-12\n");
    return 2;
  }
  std::vector<std::string> errors;
  try {
    Checker::lint(schema, "#");
    Checker(schema).check(schema, instance, "", errors);
  } catch (const SchemaError& e) {
    std::fprintf(stderr, "schema_check: bad schema: %s\n", e.what.c_str());
    return 2;
  }
  for (const std::string& e : errors) std::fprintf(stderr, "schema_check: %s\n", e.c_str());
  if (!errors.empty()) return 1;
  std::printf("conforms\n");
  return 0;
}
