#include "systems/profiling/json_schema.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

namespace sffd::profiling {

namespace {

using nlohmann::json;

bool has_type(const json& v, const std::string& type) {
    if (type == "object") return v.is_object();
    if (type == "array") return v.is_array();
    if (type == "string") return v.is_string();
    if (type == "boolean") return v.is_boolean();
    if (type == "null") return v.is_null();
    if (type == "number") return v.is_number();
    if (type == "integer")
        return v.is_number_integer() ||
               (v.is_number_float() && std::floor(v.get<double>()) == v.get<double>());
    return false;
}

struct Validator {
    const json& root;
    std::vector<std::string> errors;

    void fail(const std::string& where, const std::string& what) {
        errors.push_back((where.empty() ? "/" : where) + ": " + what);
    }

    const json* resolve(const std::string& ref, const std::string& where) {
        if (ref == "#") return &root;
        const std::string prefix = "#/$defs/";
        if (ref.rfind(prefix, 0) == 0 && root.contains("$defs") &&
            root["$defs"].contains(ref.substr(prefix.size())))
            return &root["$defs"][ref.substr(prefix.size())];
        fail(where, "schema: unresolvable $ref \"" + ref + "\"");
        return nullptr;
    }

    void validate(const json& schema, const json& v, const std::string& where, int depth = 0) {
        if (depth > 64) return fail(where, "schema: $ref recursion too deep");
        if (schema.is_boolean()) {
            if (!schema.get<bool>()) fail(where, "not allowed (schema false)");
            return;
        }
        if (!schema.is_object()) return fail(where, "schema: a schema must be an object or a boolean");
        static const std::set<std::string> known = {"$schema",    "$id",         "$defs",
                                                    "title",      "description", "type",
                                                    "properties", "required",    "additionalProperties",
                                                    "items",      "minimum",     "enum",
                                                    "const",      "$ref"};
        for (const auto& [k, _] : schema.items())
            if (!known.count(k)) fail(where, "schema: unsupported keyword \"" + k + "\"");

        if (schema.contains("$ref"))
            if (const json* target = resolve(schema["$ref"].get<std::string>(), where))
                validate(*target, v, where, depth + 1);
        if (schema.contains("type")) {
            const json& t = schema["type"];
            bool ok = false;
            if (t.is_string()) ok = has_type(v, t.get<std::string>());
            else
                for (const auto& one : t) ok |= has_type(v, one.get<std::string>());
            if (!ok) fail(where, v.dump().substr(0, 60) + " is not of type " + t.dump());
        }
        if (schema.contains("const") && v != schema["const"])
            fail(where, v.dump().substr(0, 60) + " is not " + schema["const"].dump());
        if (schema.contains("enum")) {
            bool found = false;
            for (const auto& e : schema["enum"]) found |= e == v;
            if (!found) fail(where, v.dump().substr(0, 60) + " is not one of " + schema["enum"].dump());
        }
        if (schema.contains("minimum") && v.is_number() && v.get<double>() < schema["minimum"].get<double>())
            fail(where, v.dump() + " is below the minimum " + schema["minimum"].dump());
        if (v.is_object()) {
            if (schema.contains("required"))
                for (const auto& r : schema["required"])
                    if (!v.contains(r.get<std::string>()))
                        fail(where, "missing required property \"" + r.get<std::string>() + "\"");
            const json* props = schema.contains("properties") ? &schema["properties"] : nullptr;
            for (const auto& [k, value] : v.items()) {
                if (props && props->contains(k)) {
                    validate((*props)[k], value, where + "/" + k, depth + 1);
                } else if (schema.contains("additionalProperties")) {
                    validate(schema["additionalProperties"], value, where + "/" + k, depth + 1);
                }
            }
        }
        if (v.is_array() && schema.contains("items"))
            for (std::size_t i = 0; i < v.size(); ++i)
                validate(schema["items"], v[i], where + "/" + std::to_string(i), depth + 1);
    }
};

}  // namespace

std::vector<std::string> validate_json(const std::string& schema_text, const std::string& instance_text) {
    const json schema = json::parse(schema_text, nullptr, false);
    if (schema.is_discarded()) return {"schema: not valid JSON"};
    const json instance = json::parse(instance_text, nullptr, false);
    if (instance.is_discarded()) return {"instance: not valid JSON"};
    Validator val{schema, {}};
    val.validate(schema, instance, "");
    return val.errors;
}

}  // namespace sffd::profiling
