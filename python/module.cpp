// The `hil` Python module (docs/python.md). Bad input raises hil.FormatError (a ValueError) with
// the C++ message naming file, line, column and field, and those as attributes.
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include <hil/error/error.hpp>

namespace py = pybind11;

namespace {
// Created once at import and never freed: a static py::object would be released after the
// interpreter is gone.
py::exception<hil::error::FormatError>* format_error = nullptr;
}  // namespace

PYBIND11_MODULE(hil, m) {
  m.doc() = "hil: runs and rig files as numpy arrays; contact identification, diagnosis and elastostatic calibration";
  m.attr("__version__") = HIL_VERSION;

  format_error = new py::exception<hil::error::FormatError>(m, "FormatError", PyExc_ValueError);
  format_error->doc() = "Bad input: the message reads FILE:LINE:COL: field 'F': MESSAGE; also as attributes file, line, "
                        "column (1-based, 0 = not applicable), field and message.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const hil::error::FormatError& e) {
      py::object err = py::handle(format_error->ptr())(e.what());  // an instance, to carry the location
      const auto& w = e.where();
      err.attr("file") = w.file;
      err.attr("line") = w.line;
      err.attr("column") = w.column;
      err.attr("field") = w.field;
      err.attr("message") = e.message();
      PyErr_SetObject(format_error->ptr(), err.ptr());
    }
  });

  hil::python::add_readers(m);
  hil::python::add_numerics(m);
}
