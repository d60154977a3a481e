#pragma once
/// \file The parts of the `hil` module, each registering its functions (docs/python.md).
#include <pybind11/pybind11.h>

#include <filesystem>

namespace hil::python {

namespace py = pybind11;
/// Path arguments: a str or any os.PathLike (pathlib.Path).
using Path = std::filesystem::path;

/// read_samples, read_run, read_rig: the strict readers of hil::format into numpy arrays and dicts.
void add_readers(py::module_& m);
/// identify_contact, diagnose, identify_stiffness: the command's numerics, results as dicts.
void add_numerics(py::module_& m);

}  // namespace hil::python
