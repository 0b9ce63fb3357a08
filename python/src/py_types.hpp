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

// A model with its own workspace.
struct PyModel {
  explicit PyModel(Model m) : model(std::move(m)), data(model) {}
  Model model;
  Data data;
};

// Base parameters with the model they were computed for (possibly a snapped copy).
struct PyBase {
  std::shared_ptr<PyModel> model;
  BaseParameters bp;
  std::vector<std::string> snapped;
  Eigen::MatrixXd W;  // work
  Eigen::VectorXd wK, wP;
};

}  // namespace mindyn
