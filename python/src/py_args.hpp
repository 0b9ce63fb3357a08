// The bindings' guards: per-sample arrays of shape (n,) or (m, n), classical parameter vectors
// and vectors of their sizes, so that no binding reads or writes out of bounds. Every failure is
// an ArgumentError naming the argument. The checks that make an input usable (finite values,
// ranges, choices) and the user's messages are the Python layer's (mindyn/_args.py), which the
// public functions call first.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"
#include "py_types.hpp"

namespace mindyn::pyargs {

namespace py = pybind11;

/// A binding's argument that is not what it must be: mindyn.ArgumentError in Python (a
/// mindyn.Error, ValueError and TypeError).
class ArgumentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMap = Eigen::Map<const RowMajor>;

inline std::string shapeOf(const Array& a) {
  std::string s = "(";
  for (long d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// Number of samples of a per-sample argument: -1 for a single sample of shape (n,), m >= 0 for
/// a batch of shape (m, n) (an empty batch, m = 0, included).
inline long samples(const Array& a, long n, const char* name) {
  const std::string want = std::to_string(n);
  if (a.ndim() == 1) {
    if (a.shape(0) != n)
      throw ArgumentError(std::string(name) + " has shape " + shapeOf(a) + "; expected (" + want +
                          ",) or (m, " + want + ")");
    return -1;
  }
  if (a.ndim() == 2) {
    if (a.shape(1) != n)
      throw ArgumentError(std::string(name) + " has shape " + shapeOf(a) + "; expected (m, " +
                          want + ")");
    return a.shape(0);
  }
  throw ArgumentError(std::string(name) + " must be 1-D (n,) or 2-D (m, n), got " +
                      std::to_string(a.ndim()) + "-D");
}

/// A group of per-sample arguments of width n, checked together: all single samples of shape
/// (n,) or all batches of one length m >= 0, shape (m, n). Outputs get a
/// leading axis of length m for a batch (none for a single sample), and forEach visits the m
/// samples (none for an empty batch); perSample below is the loop the bindings use.
class SampleBatch {
 public:
  SampleBatch(std::initializer_list<std::pair<const Array*, const char*>> args, long n) : n_(n) {
    long m = -2;
    for (const auto& [a, name] : args) {
      const long s = samples(*a, n, name);
      if (m == -2)
        m = s;
      else if (s != m)
        throw ArgumentError(std::string(name) +
                            ": all inputs must be single samples or batches of equal length");
      args_.push_back(a);
    }
    m_ = m;
    x_.assign(args_.size(), Eigen::VectorXd(n));
  }
  bool single() const { return m_ < 0; }
  /// Number of samples visited: 1 for a single sample, m for a batch.
  long count() const { return single() ? 1 : m_; }
  /// An output array of per-sample shape `shape`, with the leading batch axis if any.
  py::array_t<double> output(std::vector<py::ssize_t> shape) const {
    if (!single()) shape.insert(shape.begin(), m_);
    return py::array_t<double>(shape);
  }
  /// Calls f(i, x) for each sample i, x[j] the sample of the j-th argument (reused vectors).
  template <class F>
  void forEach(F&& f) {
    const long c = count();
    for (long i = 0; i < c; ++i) {
      for (size_t j = 0; j < args_.size(); ++j)
        x_[j] = Eigen::Map<const Eigen::VectorXd>(args_[j]->data() + i * n_, n_);
      f(i, static_cast<const std::vector<Eigen::VectorXd>&>(x_));
    }
  }

 private:
  long n_, m_ = -1;
  std::vector<const Array*> args_;
  std::vector<Eigen::VectorXd> x_;
};

/// The one per-sample loop of the bindings: K output arrays of per-sample shapes `shapes` (with
/// the batch's leading axis), and f(x, out) called for each sample with the GIL released, x[j]
/// the sample of the j-th argument and out[k] the start of that sample's block of output k
/// (row-major). f must not touch Python objects; the workspaces it uses must belong to the
/// calling binding (Data, SlotineLiData, ... made in the call), so that threads share none.
template <size_t K, class F>
std::array<py::array_t<double>, K> perSample(SampleBatch& batch,
                                             std::array<std::vector<py::ssize_t>, K> shapes,
                                             F&& f) {
  std::array<py::array_t<double>, K> outs;
  std::array<double*, K> start;
  std::array<long, K> size;
  for (size_t k = 0; k < K; ++k) {
    size[k] = 1;
    for (py::ssize_t d : shapes[k]) size[k] *= static_cast<long>(d);
    outs[k] = batch.output(shapes[k]);
    start[k] = outs[k].mutable_data();
  }
  {
    py::gil_scoped_release release;
    batch.forEach([&](long i, const auto& x) {
      std::array<double*, K> out;
      for (size_t k = 0; k < K; ++k) out[k] = start[k] + i * size[k];
      f(x, out);
    });
  }
  return outs;
}

/// The r x c row-major block at `p` (one sample of a matrix output of perSample).
inline Eigen::Map<RowMajor> rowMajor(double* p, long r, long c) {
  return Eigen::Map<RowMajor>(p, r, c);
}

/// The n entries at `p` (one sample of a vector output of perSample).
inline Eigen::Map<Eigen::VectorXd> vectorAt(double* p, long n) {
  return Eigen::Map<Eigen::VectorXd>(p, n);
}

/// A vector argument of exactly n entries.
inline Eigen::VectorXd vectorArg(const Eigen::VectorXd& v, long n, const char* name) {
  if (v.size() != n)
    throw ArgumentError(std::string(name) + " has " + std::to_string(v.size()) +
                        " entries; expected " + std::to_string(n));
  return v;
}

/// A 1-D parameter vector of exactly `size` entries (p of a base set, for instance).
inline Eigen::Map<const Eigen::VectorXd> parameterArg(const Array& a, long size, const char* name) {
  if (a.ndim() != 1 || a.shape(0) != size)
    throw ArgumentError(std::string(name) + " has shape " + shapeOf(a) + "; expected (" +
                        std::to_string(size) + ",)");
  return Eigen::Map<const Eigen::VectorXd>(a.data(), size);
}

/// A classical parameter vector for `self`'s model. None: the model's own values in `layout`.
/// With `layout_given` the size must fit `layout`; otherwise the layout is read off the size
/// (10, 11, 10 + c or 11 + c entries per joint, c the friction model's columns) and returned in
/// `layout`.
inline Eigen::VectorXd classicalParameters(const PyModel& self, const py::object& params,
                                           ParameterLayout& layout, bool layout_given) {
  const int n = self.model.nq();
  if (params.is_none()) {
    checkDriveSide(self.model, layout);
    return self.model.parameters(layout);
  }
  Array a = params.cast<Array>();
  if (a.ndim() != 1) throw ArgumentError("params must be 1-D");
  const long size = a.shape(0);
  if (layout_given) {
    if (size != layout.size(n))
      throw ArgumentError("params has " + std::to_string(size) + " entries; this layout expects " +
                          std::to_string(layout.size(n)));
  } else {
    layout = self.model.layoutOfSize(size);
  }
  checkDriveSide(self.model, layout);
  return Eigen::Map<const Eigen::VectorXd>(a.data(), size);
}

/// A homogeneous 4x4 matrix as an isometry (its last row is not read).
inline Eigen::Isometry3d isometry(const Eigen::Matrix4d& M) {
  Eigen::Isometry3d T;
  T.matrix() = M;
  return T;
}

}  // namespace mindyn::pyargs
