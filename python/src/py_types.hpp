// The C++ objects behind the Python classes Model and BaseParameters, shared by the binding
// translation units (bindings.cpp, bind_*.cpp).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "mindyn/base_parameters.hpp"
#include "mindyn/data.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

// A model. It holds no workspace: every binding call makes its own Data (and whatever other
// workspace it needs), so that calls from several threads, which run with the GIL released, never
// share one. The geometry and gravity are never changed after construction (the parameter
// setters change only the inertial, rotor and friction values, read with the GIL held).
struct PyModel {
  explicit PyModel(Model m) : model(std::move(m)) {}
  Model model;
};

// Base parameters with the model they were computed for (possibly a snapped copy).
struct PyBase {
  std::shared_ptr<PyModel> model;
  BaseParameters bp;
  std::vector<std::string> snapped;
};

}  // namespace mindyn
