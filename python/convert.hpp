#pragma once
/// \file C++ values -> Python objects for the `hil` module: JSON trees into dicts and lists (the
/// command's JSON builders are reused rather than writing each field twice), Eigen and vectors of
/// samples into numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hil::python {

namespace py = pybind11;

/// null -> None, numbers, strings, arrays -> list, objects -> dict.
py::object to_python(const nlohmann::json& j);

/// A (rows, cols) float64 array filled by `get(row, col)`.
template <class Get>
py::array_t<double> matrix(std::size_t rows, std::size_t cols, Get get) {
  py::array_t<double> a({rows, cols});
  auto m = a.mutable_unchecked<2>();
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < cols; ++c) m(static_cast<py::ssize_t>(r), static_cast<py::ssize_t>(c)) = get(r, c);
  return a;
}

/// A (n,) float64 array filled by `get(i)`.
template <class Get>
py::array_t<double> column(std::size_t n, Get get) {
  py::array_t<double> a(static_cast<py::ssize_t>(n));
  auto m = a.mutable_unchecked<1>();
  for (std::size_t i = 0; i < n; ++i) m(static_cast<py::ssize_t>(i)) = get(i);
  return a;
}

py::array_t<double> array(const Eigen::MatrixXd& m);
py::array_t<double> array(const Eigen::VectorXd& v);
py::array_t<double> array(const Eigen::Vector3d& v);
py::array_t<double> array(const std::vector<double>& v);
/// A 4x4 homogeneous matrix.
py::array_t<double> homogeneous(const Eigen::Isometry3d& T);

}  // namespace hil::python
