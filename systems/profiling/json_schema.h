// A small JSON Schema validator for the subset profile.schema.json uses (draft 2020-12 keywords):
// type (string or list; "integer" = a number with no fractional part), properties, required,
// additionalProperties (boolean or schema), items (schema), minimum, enum, const, $ref to "#/$defs/..."
// or "#", and the annotations $schema, $id, $defs, title, description. Any other keyword is reported as
// an error, so the validator never silently ignores a constraint it does not implement. As in JSON
// Schema, object keywords apply only to objects, minimum only to numbers, items only to arrays.
#pragma once

#include <string>
#include <vector>

namespace sffd::profiling {

// Returns one message per violation ("/systems/0/cpu_ms/p50: -1 is below the minimum 0"); empty when
// the instance is valid. Unparsable schema or instance text is reported the same way.
std::vector<std::string> validate_json(const std::string& schema_text, const std::string& instance_text);

}  // namespace sffd::profiling
