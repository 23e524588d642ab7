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
// `source` names the object in messages; relative file names in it resolve against `base_dir`.
// \return the model.
// \throw InvalidInputError "SOURCE: KEY: problem" for an unknown type, an unknown, missing or
//        mistyped key (with the nearest spelling), or a model that refuses its values;
//        FileError for a file it names (a scan) that cannot be read.
std::unique_ptr<Field> make_field(const nlohmann::json& spec, const std::string& source,
                                  const std::filesystem::path& base_dir = {});
std::unique_ptr<Field> make_field(JsonReader& reader);

// Reads a field JSON file; relative paths inside it resolve against the file's folder.
// \throw FileError for a file that cannot be opened or read; InvalidInputError "FILE: problem"
//        for malformed JSON (a key given twice included) and as make_field.
std::unique_ptr<Field> load_field(const std::filesystem::path& path);

}  // namespace cdp
