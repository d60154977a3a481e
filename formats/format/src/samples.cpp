#include <hil/format/samples.hpp>

#include <fmt/format.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <hil/format/csv.hpp>
#include <hil/error/error.hpp>
#include <hil/format/quaternion.hpp>

namespace hil::format {

const std::vector<std::string>& sample_columns() {
  static const std::vector<std::string> cols{"t",  "px", "py", "pz", "qw", "qx", "qy", "qz", "vx", "vy",
                                             "vz", "wx", "wy", "wz", "fx", "fy", "fz", "mx", "my", "mz"};
  return cols;
}

namespace {

bool is_joint_column(const std::string& name) {
  return name.size() >= 2 && name[0] == 'j' && name[1] != '0' && name.find_first_not_of("0123456789", 1) == std::string::npos;
}

SampleTable from_csv(const CsvTable& csv) {
  SampleTable t;
  t.file = csv.file;
  t.line = csv.row_line;
  const auto n = csv.rows();
  if (n == 0) throw error::FormatError({csv.file, 0, 0, ""}, "no samples: the file has a header but no data rows");

  // Joints: j1..jN, numbered without gaps.
  std::size_t nj = 0;
  for (const auto& h : csv.header)
    if (is_joint_column(h)) nj = std::max<std::size_t>(nj, std::stoul(h.substr(1)));
  for (std::size_t j = 1; j <= nj; ++j)
    if (!csv.is_numeric("j" + std::to_string(j)))
      throw error::FormatError({csv.file, csv.row_line.front() - 1, 0, "j" + std::to_string(j)},
                               "joint columns must run j1..j" + std::to_string(nj) + " without gaps");
  t.extra_columns = csv.text_columns();

  auto col = [&](const char* c) { return csv.numeric(c).data(); };
  const double *T = col("t"), *px = col("px"), *py = col("py"), *pz = col("pz"), *qw = col("qw"), *qx = col("qx"), *qy = col("qy"),
               *qz = col("qz"), *vx = col("vx"), *vy = col("vy"), *vz = col("vz"), *wx = col("wx"), *wy = col("wy"), *wz = col("wz"),
               *fx = col("fx"), *fy = col("fy"), *fz = col("fz"), *mx = col("mx"), *my = col("my"), *mz = col("mz");
  std::size_t qw_col = 0;
  for (std::size_t c = 0; c < csv.header.size(); ++c)
    if (csv.header[c] == "qw") qw_col = c + 1;

  t.samples.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Sample& s = t.samples[i];
    s.t_s = T[i];
    if (i > 0) {
      if (T[i] < T[i - 1])
        throw error::FormatError({csv.file, csv.row_line[i], 0, "t"},
                                 fmt::format("time goes backwards: {} after {} (line {})", T[i], T[i - 1], csv.row_line[i - 1]));
      if (T[i] == T[i - 1])
        throw error::FormatError({csv.file, csv.row_line[i], 0, "t"},
                                 fmt::format("duplicated timestamp {} (also on line {})", T[i], csv.row_line[i - 1]));
    }
    const auto q = checked_unit_quaternion(qw[i], qx[i], qy[i], qz[i]);
    if (!q)
      throw error::FormatError({csv.file, csv.row_line[i], qw_col, "qw qx qy qz"},
                               fmt::format("not a unit quaternion: norm {:.6g} (expected 1 within {})",
                                           std::sqrt(qw[i] * qw[i] + qx[i] * qx[i] + qy[i] * qy[i] + qz[i] * qz[i]),
                                           kQuaternionNormTolerance));
    s.q_world_ee = *q;
    s.p_world_ee_m = {px[i], py[i], pz[i]};
    s.v_world_ee_m_per_s = {vx[i], vy[i], vz[i]};
    s.w_world_ee_rad_per_s = {wx[i], wy[i], wz[i]};
    s.f_fp_n = {fx[i], fy[i], fz[i]};
    s.m_fp_nm = {mx[i], my[i], mz[i]};
  }
  t.joints_rad.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(nj));
  for (std::size_t j = 0; j < nj; ++j) {
    const auto& c = csv.numeric("j" + std::to_string(j + 1));
    for (std::size_t i = 0; i < n; ++i) t.joints_rad(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = c[i];
  }
  return t;
}

CsvOptions sample_options(const std::string& name) {
  CsvOptions o;
  o.required = sample_columns();
  o.numeric_if_present = is_joint_column;
  o.display_name = name;
  return o;
}

}  // namespace

SampleTable read_samples(const std::string& path) { return from_csv(read_csv(path, sample_options(path))); }

SampleTable parse_samples(const std::string& text, const std::string& display_name) {
  return from_csv(parse_csv(text, sample_options(display_name)));
}

SamplesWriter::SamplesWriter(const std::string& path, std::size_t joint_count, std::vector<std::string> extra_columns)
    : path_(path), joints_(joint_count), extras_(extra_columns.size()) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  std::string header;
  for (const auto& c : sample_columns()) header += (header.empty() ? "" : ",") + c;
  for (std::size_t j = 1; j <= joints_; ++j) header += ",j" + std::to_string(j);
  for (const auto& e : extra_columns) header += "," + e;
  header += '\n';
  write_all(header);
}

SamplesWriter::~SamplesWriter() {
  try {
    close();
  } catch (...) {
    // Destructors must not throw; call close() to see write errors.
  }
}

void SamplesWriter::append(const Sample& s, const double* joints_rad, const double* extras) {
  // {} prints the shortest text that reads back to the same double: the file is lossless.
  auto out = std::back_inserter(buf_);
  fmt::format_to(out, "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", s.t_s, s.p_world_ee_m.x(), s.p_world_ee_m.y(),
                 s.p_world_ee_m.z(), s.q_world_ee.w(), s.q_world_ee.x(), s.q_world_ee.y(), s.q_world_ee.z(), s.v_world_ee_m_per_s.x(),
                 s.v_world_ee_m_per_s.y(), s.v_world_ee_m_per_s.z(), s.w_world_ee_rad_per_s.x(), s.w_world_ee_rad_per_s.y(),
                 s.w_world_ee_rad_per_s.z(), s.f_fp_n.x(), s.f_fp_n.y(), s.f_fp_n.z(), s.m_fp_nm.x(), s.m_fp_nm.y(), s.m_fp_nm.z());
  for (std::size_t j = 0; j < joints_; ++j) fmt::format_to(out, ",{}", joints_rad[j]);
  for (std::size_t e = 0; e < extras_; ++e) fmt::format_to(out, ",{}", extras[e]);
  buf_ += '\n';
  ++rows_;
  if (buf_.size() > (1u << 20)) flush();  // bound memory if the caller never flushes
}

void SamplesWriter::write_all(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const auto n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
    }
    done += static_cast<std::size_t>(n);
  }
}

void SamplesWriter::flush() {
  if (fd_ < 0 || buf_.empty()) return;
  write_all(buf_);
  buf_.clear();
}

void SamplesWriter::close() {
  if (fd_ < 0) return;
  flush();
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) throw std::runtime_error(path_ + ": close failed: " + std::strerror(errno));
}

void write_samples(const std::string& path, const SampleTable& table) {
  SamplesWriter w(path, table.joint_count());
  std::vector<double> q(table.joint_count());
  for (std::size_t i = 0; i < table.size(); ++i) {
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = table.joints_rad(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    w.append(table.samples[i], q.data());
  }
  w.close();
}

}  // namespace hil::format
