// Compiled models: C++ functors of the point whose gradient and Hessian come from automatic
// differentiation (src/models/compiled_models.cpp, where adding one is one functor and one
// line). The field factory of cdp::io offers each under its name as a JSON type.
#pragma once

#include <cdp/core/field.h>

#include <functional>
#include <map>
#include <memory>
#include <string>

namespace cdp {

using CompiledModelMaker = std::function<std::unique_ptr<Field>()>;

// Every compiled model by name, each made with its default box.
std::map<std::string, CompiledModelMaker> compiled_models();

}  // namespace cdp
