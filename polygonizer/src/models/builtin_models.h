// Builders of the compiled models (compiled_models.cpp), collected by the field factory.
#pragma once

#include <polygonizer/field_factory.h>

#include <map>
#include <string>

namespace cdp {

std::map<std::string, FieldBuilder> compiled_model_builders();

}  // namespace cdp
