// One factory for every field model: reads a JSON object {"type": ..., ...} into a Field.
// Model types register a builder under their type name; see README.md for adding one.
#pragma once

#include <cdp/core/field.h>
#include <cdp/io/json_reader.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cdp {

// A builder reads its keys from the reader (the "type" and "bounds" keys are handled for it)
// and returns the model.
using FieldBuilder = std::function<std::unique_ptr<Field>(JsonReader&)>;

// Registers a model type; a second registration of the same name replaces the first.
void register_field_type(const std::string& type, FieldBuilder builder);
std::vector<std::string> registered_field_types();

// Builds a field from a JSON object. An optional "bounds" overrides the model's own box.
std::unique_ptr<Field> make_field(const nlohmann::json& spec, const std::string& source,
                                  const std::filesystem::path& base_dir = {});
std::unique_ptr<Field> make_field(JsonReader& reader);

// Reads a field JSON file; relative paths inside it resolve against the file's folder.
std::unique_ptr<Field> load_field(const std::filesystem::path& path);

}  // namespace cdp
