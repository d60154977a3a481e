#pragma once
/// \file The rig file (`rig.yaml`): frames, robot, object geometry, devices, nominal model.
/// Every field is documented in docs/formats.md. Plain data: the numerics modules build their own
/// models from it, the drivers their device configurations.
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hil::format {

/// A rigid transform T_parent_child: a point p_child maps to rotation * p_child + translation_m.
struct Pose {
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Isometry3d isometry() const;
  static Pose from_isometry(const Eigen::Isometry3d& T);
};

/// A named frame placed relative to its parent (`world`, `ee` or another named frame).
struct FrameSpec {
  std::string name;
  std::string parent;
  Pose T_parent_frame;
};

/// How the robot's joints are given: a DH table (standard or modified) or a URDF's joints.
enum class DhConvention { standard, modified, urdf };
/// "standard", "modified", "urdf".
const char* convention_name(DhConvention c);
enum class JointType { revolute, prismatic };

/// One row of a DH table. Standard (Denavit-Hartenberg 1955): T = Rz(θ) Tz(d) Tx(a) Rx(α);
/// modified (Craig): T = Rx(α) Tx(a) Rz(θ) Tz(d). θ = q + theta_offset for revolute joints.
/// A URDF joint (DhConvention::urdf): T = T_parent_joint · Rot(axis, θ) (prismatic: · Trans(axis, d)),
/// a_m and alpha_rad unused.
struct DhJointSpec {
  std::string name;
  JointType type = JointType::revolute;
  double a_m = 0.0;
  double alpha_rad = 0.0;
  double d_m = 0.0;
  double theta_offset_rad = 0.0;
  double lower = -3.141592653589793;                ///< rad or m
  double upper = 3.141592653589793;                 ///< rad or m
  Pose T_parent_joint;                              ///< URDF: the joint frame in the previous body's frame
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< URDF: unit axis in the joint frame
  /// URDF `<mimic>`: this joint's value is mimic_multiplier · q(mimic_of) + mimic_offset, where
  /// mimic_of names an independent joint of the same chain; empty for an independent joint.
  std::string mimic_of;
  double mimic_multiplier = 1.0;
  double mimic_offset = 0.0;  ///< rad or m, in this joint's unit
};

/// A body's mass properties in its frame (URDF inertials, fixed links lumped in).
struct InertialSpec {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_kgm2 = Eigen::Matrix3d::Zero();  ///< about the centre of mass
};

struct RobotSpec {
  std::string name;
  DhConvention convention = DhConvention::standard;
  std::vector<DhJointSpec> joints;
  Pose T_world_base;  ///< robot base in world
  Pose T_flange_ee;   ///< end-effector (tool) frame in the last joint's body frame
  /// URDF robots: the file (as resolved), the chain's ends, the links of bodies 0..N (the link each
  /// body's frame is; fixed links are lumped into the one they hang from) and their inertials.
  std::string urdf_file;
  std::string base_link;
  std::string tip_link;
  std::vector<std::string> body_links;
  std::vector<InertialSpec> inertials;
};

/// A convex polyhedron given by its vertices in the object frame. Faces are derived by the
/// geometry code (contact_id); here only non-degeneracy is checked.
struct PolyhedronSpec {
  std::vector<Eigen::Vector3d> vertices_m;
  std::size_t line = 0;  ///< where it was declared, for messages
};

struct FeatureSpec {
  std::string name;
  std::vector<PolyhedronSpec> polyhedra;
};

struct ObjectSpec {
  std::string name;
  std::string frame;  ///< the frame the vertices are expressed in (e.g. object1, object2)
  std::vector<FeatureSpec> features;
  std::size_t polyhedron_count() const;
};

/// One geometric uncertainty of a feature (the contact paper's x_u entries).
struct UncertaintySpec {
  enum class Kind { translation, rotation };
  std::string name;
  std::string object;
  std::string feature;
  Kind kind = Kind::translation;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();    ///< unit, object frame
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();  ///< a point on the rotation axis, object frame
  double design_value = 0.0;                          ///< x_u^d, m or rad
  double prior_std = 0.0;                             ///< expected size of the error (m or rad); 0 = not given
};

struct ContactModelSpec {
  double stiffness_n_per_m = 0.0;            ///< K > 0
  double friction_coefficient = 0.0;         ///< μ ≥ 0
  double sticking_threshold_m_per_s = 1e-3;  ///< v_t,m
  double force_scale_n = 0.0;                ///< F_max for the W_Y weighting; 0 = from data
  double moment_scale_nm = 0.0;              ///< M_max for the W_Y weighting; 0 = from data
};

struct ModelSpec {
  std::optional<ContactModelSpec> contact;
  std::vector<UncertaintySpec> uncertainties;
};

/// A signal decoded from CAN frames by the declarative force-plate decoder.
struct CanSignalSpec {
  std::string component;  ///< fx fy fz mx my mz, or status
  std::uint32_t frame_id = 0;
  bool extended_id = false;
  unsigned start_bit = 0;  ///< bit index: little endian = Intel LSB numbering; big endian = Motorola MSB
  unsigned length_bits = 16;
  bool is_signed = true;
  bool big_endian = false;
  double scale = 1.0;
  double offset = 0.0;
};

struct ForcePlateDeviceSpec {
  std::string protocol = "ati_netcanoem";  ///< ati_netcanoem | declarative | ati_netft_rdt | ati_netft_can | robotiq_ft300
  std::string interface = "vcan0";         ///< SocketCAN interface name (CAN protocols)
  std::uint32_t base_id = 0x20;            ///< NETCANOEM base id (11-bit id = base << 4 | opcode); factory 0x20
  std::string host;                        ///< ati_netft_rdt: the box's IPv4 address
  int port = 49152;                        ///< ati_netft_rdt: RDT UDP port
  std::string calibration_xml;             ///< ati_netft_rdt: the box's netftapi2.xml saved to a file (rig-relative)
  double counts_per_force = 0.0;           ///< ati_netft_rdt without calibration_xml; ati_netft_can (required)
  double counts_per_torque = 0.0;
  std::string force_unit = "N", torque_unit = "Nm";
  std::string serial_device;  ///< robotiq_ft300: the serial port
  int baud = 19200;           ///< robotiq_ft300
  int slave = 9;              ///< robotiq_ft300: Modbus slave id
  /// robotiq_ft300: the writes hil may make, by name; only "stream_start" (0x0200 to register
  /// 410) exists. Without it the sensor is only read.
  std::vector<std::string> allowed_writes;
  double rate_hz = 1000.0;                ///< robotiq_ft300: 100 streaming (the sensor's), 50 polling, by default
  Pose T_fp_sensor;                       ///< sensor frame in the force-plate frame
  std::vector<CanSignalSpec> signals;     ///< declarative protocol only
  std::vector<double> saturation_limits;  ///< |fx..mz| limits (N, N·m); empty = unknown
  /// The calibration's scale accuracy: the largest relative error of one component's scale against
  /// another's that the lab trusts the plate to. The diagnosis does not explain a run by a
  /// `sensor_gain` beyond it (docs/diagnosis.md, "A plate's calibration tolerance").
  double gain_tolerance = 0.15;
};

/// One quantity read from the robot controller's registers.
struct RegisterEntrySpec {
  std::string quantity;  ///< j1..jN (rad), px py pz (m), rx ry rz (rotation vector, rad)
  unsigned address = 0;
  std::string table = "holding";   ///< holding | input
  std::string type = "int16";      ///< int16 uint16 int32 uint32 float32
  std::string word_order = "big";  ///< for 32-bit types: big = high word first
  double scale = 1.0;              ///< value = raw * scale + offset
  double offset = 0.0;
};

struct RobotControllerSpec {
  std::string transport = "tcp";  ///< tcp | rtu
  std::string host = "127.0.0.1";
  int port = 502;
  int unit_id = 1;
  std::string serial_device;  ///< rtu
  int baud = 115200;
  char parity = 'N';
  int data_bits = 8;
  int stop_bits = 1;
  double rate_hz = 125.0;
  double timeout_s = 0.2;
  std::string register_map = "ur";           ///< ur | float32 | custom
  std::vector<RegisterEntrySpec> registers;  ///< custom map
};

struct DevicesSpec {
  std::optional<ForcePlateDeviceSpec> force_plate;
  std::optional<RobotControllerSpec> robot;
};

/// The names the frame tree has on ROS topics (/tf, /tf_static, header.frame_id): the rig file's
/// `tf:` section. Inside the rig file the frames stay `world` and `ee` (docs/ros.md).
struct TfNames {
  std::string world = "world";
  std::string base = "robot_base";  ///< the robot's base; a URDF robot's default is its chain's base link
  std::string ee = "ee";
  /// A rig frame's name on ROS topics: `world` and `ee` renamed, every other frame as it is.
  const std::string& ros(const std::string& rig_frame) const;
};

struct RigSpec {
  int format_version = 1;
  std::string name;
  std::string source;  ///< file it was read from
  std::vector<FrameSpec> frames;
  std::optional<RobotSpec> robot;
  std::vector<ObjectSpec> objects;
  DevicesSpec devices;
  ModelSpec model;
  TfNames tf;

  const FrameSpec* frame(const std::string& name) const;
  const ObjectSpec* object(const std::string& name) const;
  /// T_world_frame for frames whose chain ends at `world` (not through `ee`).
  /// \throws error::FormatError if the frame is unknown or hangs off the moving end-effector.
  Eigen::Isometry3d T_world(const std::string& frame) const;
  /// T_ee_frame for frames whose chain ends at `ee`.
  Eigen::Isometry3d T_ee(const std::string& frame) const;
};

/// Reads and checks a rig file. \throws error::FormatError naming file, line and field.
RigSpec load_rig(const std::string& path);
/// Same on YAML text (`display_name` names it in messages).
RigSpec parse_rig(const std::string& yaml_text, const std::string& display_name);

/// Number of polyhedra and features over all objects.
std::size_t total_polyhedra(const RigSpec& rig);
std::size_t total_features(const RigSpec& rig);

}  // namespace hil::format
