#include "convert.hpp"

#include <stdexcept>

namespace hil::python {

py::object to_python(const nlohmann::json& j) {
  using V = nlohmann::json::value_t;
  switch (j.type()) {
    case V::null:
    case V::discarded: return py::none();
    case V::boolean: return py::bool_(j.get<bool>());
    case V::number_integer: return py::int_(j.get<std::int64_t>());
    case V::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case V::number_float: return py::float_(j.get<double>());
    case V::string: return py::str(j.get_ref<const std::string&>());
    case V::array: {
      py::list l;
      for (const auto& e : j) l.append(to_python(e));
      return l;
    }
    case V::object: {
      py::dict d;
      for (const auto& [k, v] : j.items()) d[py::str(k)] = to_python(v);
      return d;
    }
    case V::binary: break;
  }
  throw std::logic_error("hil: a JSON value of binary type has no Python form");
}

py::array_t<double> array(const Eigen::MatrixXd& m) {
  return matrix(static_cast<std::size_t>(m.rows()), static_cast<std::size_t>(m.cols()),
                [&](std::size_t r, std::size_t c) { return m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)); });
}

py::array_t<double> array(const Eigen::VectorXd& v) {
  return column(static_cast<std::size_t>(v.size()), [&](std::size_t i) { return v[static_cast<Eigen::Index>(i)]; });
}

py::array_t<double> array(const Eigen::Vector3d& v) {
  return column(3, [&](std::size_t i) { return v[static_cast<Eigen::Index>(i)]; });
}

py::array_t<double> array(const std::vector<double>& v) {
  return column(v.size(), [&](std::size_t i) { return v[i]; });
}

py::array_t<double> homogeneous(const Eigen::Isometry3d& T) {
  const Eigen::Matrix4d M = T.matrix();
  return matrix(4, 4, [&](std::size_t r, std::size_t c) { return M(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)); });
}

}  // namespace hil::python
