#include <gtest/gtest.h>

#include <hil/format/rig.hpp>
#include <hil/test/files.hpp>

using hil::format::parse_rig;
using hil::test::fails_with;

namespace {
// A minimal valid rig; tests break one thing at a time.
const std::string kRig = R"(format_version: 1
name: t
frames:
  - {name: force_plate, parent: world, translation_m: [0, 0, 0.1]}
  - {name: object2, parent: force_plate, rpy_rad: [0, 0, 1.5707963267948966]}
  - {name: object1, parent: ee}
objects:
  - name: a
    frame: object1
    features:
      - name: f1
        polyhedra:
          - vertices_m: [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
model:
  contact: {stiffness_n_per_m: 1.0e5, friction_coefficient: 0.3}
)";
auto parse(const std::string& text) {
  return [text] { parse_rig(text, "rig.yaml"); };
}
std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}
}  // namespace

TEST(Rig, ReadsAndResolvesFrames) {
  const auto rig = parse_rig(kRig, "rig.yaml");
  EXPECT_EQ(rig.name, "t");
  ASSERT_EQ(rig.objects.size(), 1u);
  EXPECT_EQ(hil::format::total_polyhedra(rig), 1u);
  const auto T = rig.T_world("object2");
  EXPECT_NEAR(T.translation().z(), 0.1, 1e-15);
  EXPECT_NEAR((T.linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_TRUE(rig.T_ee("object1").isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_DOUBLE_EQ(rig.model.contact->friction_coefficient, 0.3);
}

TEST(Rig, ShippedExampleIsValid) {
  const auto rig = hil::format::load_rig(std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml");
  ASSERT_TRUE(rig.robot.has_value());
  EXPECT_EQ(rig.robot->joints.size(), 6u);
  EXPECT_TRUE(rig.devices.force_plate.has_value());
  EXPECT_EQ(rig.model.uncertainties.size(), 2u);
}

TEST(Rig, UnknownFieldIsNamedWithSuggestion) {
  EXPECT_TRUE(fails_with(parse(replace(kRig, "name: t\n", "name: t\nnmae: x\n")), 3, "nmae", "did you mean 'name'"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "friction_coefficient", "friction_coeficient")), 0, "model.contact.friction_coeficient",
                         "unknown field"));
}

TEST(Rig, MissingFieldIsNamed) {
  EXPECT_TRUE(fails_with(parse(replace(kRig, "name: t\n", "")), 0, "name", "required field is missing"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "    frame: object1\n", "")), 8, "objects[0].frame", "required field is missing"));
}

TEST(Rig, DegeneratePolyhedra) {
  EXPECT_TRUE(fails_with(parse(replace(kRig, "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]", "[[0, 0, 0], [1, 0, 0], [0, 1, 0]]")), 13,
                         "objects[0].features[0].polyhedra[0].vertices_m", "at least 4 non-coplanar"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]",
                                       "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]]")),
                         13, "", "coplanar"));
}

TEST(Rig, BadValues) {
  EXPECT_TRUE(fails_with(parse(replace(kRig, "stiffness_n_per_m: 1.0e5", "stiffness_n_per_m: -5")), 0, "model.contact.stiffness_n_per_m",
                         "K must be > 0"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "friction_coefficient: 0.3", "friction_coefficient: -0.1")), 0, "", ">= 0"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "[0, 0, 0.1]", "[0, zero, 0.1]")), 4, "", "expected a number, found 'zero'"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "[0, 0, 0.1]", "[0, .nan, 0.1]")), 4, "", "finite"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "[0, 0, 0.1]", "[0, 0]")), 4, "", "list of 3 numbers"));
}

TEST(Rig, BadFrames) {
  EXPECT_TRUE(fails_with(parse(replace(kRig, "parent: force_plate", "parent: nowhere")), 0, "frames[1].parent", "unknown parent"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "{name: object1, parent: ee}", "{name: object1, parent: ee, quaternion_wxyz: [1, 1, 0, 0]}")),
                         0, "frames[2].quaternion_wxyz", "not a unit quaternion"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "frame: object1", "frame: object9")), 0, "objects[0].frame", "unknown frame"));
}

TEST(Rig, UncertaintyMustNameAnExistingFeature) {
  const auto text = kRig + "  uncertainties:\n    - {name: u1, object: a, feature: nope, kind: translation, axis: [1, 0, 0]}\n";
  EXPECT_TRUE(fails_with(parse(text), 0, "model.uncertainties[0].feature", "has no feature 'nope'"));
}

TEST(Rig, EmptyAndSyntaxErrors) {
  EXPECT_TRUE(fails_with(parse(""), 0, "", "empty rig file"));
  EXPECT_TRUE(fails_with(parse("format_version: 1\nname: [unclosed\n"), 0, "", "YAML syntax error"));
  EXPECT_TRUE(fails_with(parse(replace(kRig, "format_version: 1", "format_version: 7")), 1, "format_version", "version 1"));
}

TEST(Rig, DeviceSections) {
  const auto ok = kRig + R"(devices:
  force_plate:
    protocol: declarative
    interface: can0
    signals:
      - {component: fx, frame_id: 0x1A0, start_bit: 0, length_bits: 16, byte_order: big, scale: 0.01}
  robot: {transport: tcp, host: 127.0.0.1, port: 5020, register_map: custom, registers: [{quantity: j1, address: 270, scale: 0.001}]}
)";
  const auto rig = parse_rig(ok, "rig.yaml");
  ASSERT_EQ(rig.devices.force_plate->signals.size(), 1u);
  EXPECT_EQ(rig.devices.force_plate->signals[0].frame_id, 0x1A0u);
  EXPECT_TRUE(rig.devices.force_plate->signals[0].big_endian);
  EXPECT_EQ(rig.devices.robot->registers[0].address, 270u);
  EXPECT_TRUE(fails_with(parse(replace(ok, "port: 5020", "port: 70000")), 0, "devices.robot.port", "1..65535"));
  EXPECT_TRUE(fails_with(parse(replace(ok, "component: fx", "component: fq")), 0, "", "expected one of fx"));
  EXPECT_TRUE(fails_with(parse(replace(ok, "frame_id: 0x1A0", "frame_id: 0x1000")), 0, "", "CAN id out of range"));
}

TEST(Rig, NetCanOemDefaultsToTheFactoryBaseIdAndReadsItsEarlierName) {
  const auto rig = parse_rig(kRig + "devices:\n  force_plate: {protocol: ati_ft_can}\n", "rig.yaml");
  EXPECT_EQ(rig.devices.force_plate->protocol, "ati_netcanoem");
  EXPECT_EQ(rig.devices.force_plate->base_id, 0x20u);
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {base_id: 0x80}\n"), 0, "devices.force_plate.base_id", "0..127"));
}

TEST(Rig, ThePlatesCalibrationToleranceDefaultsTo15PercentAndMustBeARelativeError) {
  EXPECT_DOUBLE_EQ(parse_rig(kRig + "devices:\n  force_plate: {}\n", "rig.yaml").devices.force_plate->gain_tolerance, 0.15);
  EXPECT_DOUBLE_EQ(parse_rig(kRig + "devices:\n  force_plate: {gain_tolerance: 0.05}\n", "rig.yaml").devices.force_plate->gain_tolerance,
                   0.05);
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {gain_tolerance: 0}\n"), 0, "devices.force_plate.gain_tolerance", ""));
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {gain_tolerance: 15}\n"), 0, "devices.force_plate.gain_tolerance",
                         "a relative scale error"));
}

TEST(Rig, Ft300SectionsAndTheirMistakes) {
  const std::string head = kRig + "devices:\n  force_plate:\n    protocol: robotiq_ft300\n";
  const auto ro = parse_rig(head + "    serial_device: /dev/ttyUSB0\n", "rig.yaml");
  EXPECT_EQ(ro.devices.force_plate->serial_device, "/dev/ttyUSB0");
  EXPECT_EQ(ro.devices.force_plate->slave, 9);
  EXPECT_TRUE(ro.devices.force_plate->allowed_writes.empty()) << "read-only unless the rig says otherwise";
  EXPECT_EQ(ro.devices.force_plate->rate_hz, 50.0);
  const auto st = parse_rig(head + "    serial_device: /dev/ttyUSB1\n    allowed_writes: [stream_start]\n    slave: 10\n", "rig.yaml");
  ASSERT_EQ(st.devices.force_plate->allowed_writes.size(), 1U);
  EXPECT_EQ(st.devices.force_plate->rate_hz, 100.0);
  EXPECT_EQ(st.devices.force_plate->slave, 10);
  EXPECT_TRUE(fails_with(parse(head + "    rate_hz: 100\n"), 0, "devices.force_plate.serial_device", "serial port"));
  EXPECT_TRUE(fails_with(parse(head + "    serial_device: /dev/x\n    allowed_writes: [zero_sensor]\n"), 0,
                         "devices.force_plate.allowed_writes[0]", "'stream_start'"));
  EXPECT_TRUE(fails_with(parse(head + "    serial_device: /dev/x\n    baud: 115200\n"), 0, "devices.force_plate.baud", "19200"));
  EXPECT_TRUE(fails_with(parse(head + "    serial_device: /dev/x\n    slave: 0\n"), 0, "devices.force_plate.slave", "1..247"));
  EXPECT_TRUE(fails_with(parse(head + "    serial_device: /dev/x\n    interface: can0\n"), 0, "devices.force_plate.interface",
                         "serial line"));
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {protocol: ati_netcanoem, allowed_writes: [stream_start]}\n"), 0,
                         "devices.force_plate.allowed_writes", "only the robotiq_ft300 protocol"));
}

TEST(Rig, NetFtCanSectionsAndTheirMistakes) {
  const std::string head = kRig + "devices:\n  force_plate:\n    protocol: ati_netft_can\n";
  const auto rig = parse_rig(head + "    interface: can1\n    base_id: 0x7F9\n    counts_per_force: 50\n    counts_per_torque: 1000\n",
                             "rig.yaml");
  EXPECT_EQ(rig.devices.force_plate->base_id, 0x7F9U);
  EXPECT_EQ(rig.devices.force_plate->counts_per_force, 50.0);
  EXPECT_TRUE(fails_with(parse(head + "    counts_per_force: 50\n    counts_per_torque: 1000\n"), 0, "devices.force_plate.base_id",
                         "base address"));
  EXPECT_TRUE(fails_with(parse(head + "    base_id: 0x7FA\n    counts_per_force: 50\n    counts_per_torque: 1000\n"), 0,
                         "devices.force_plate.base_id", "0..0x7F9"));
  EXPECT_TRUE(fails_with(parse(head + "    base_id: 0x100\n    counts_per_force: 50\n"), 0, "devices.force_plate.counts_per_torque",
                         "16-bit CAN values"));
  EXPECT_TRUE(fails_with(parse(head + "    base_id: 0x100\n    calibration_xml: box.xml\n"), 0, "devices.force_plate.calibration_xml",
                         "is CAN"));
}

TEST(Rig, NetFtBoxSectionsAndTheirMistakes) {
  const std::string head = kRig + "devices:\n  force_plate:\n    protocol: ati_netft_rdt\n";
  const auto rig = parse_rig(head + "    host: 192.168.1.1\n    calibration_xml: box.xml\n", "rig.yaml");
  EXPECT_EQ(rig.devices.force_plate->host, "192.168.1.1");
  EXPECT_EQ(rig.devices.force_plate->port, 49152);
  EXPECT_EQ(rig.devices.force_plate->calibration_xml, "box.xml");
  const auto counts =
      parse_rig(head +
                    "    host: 10.0.0.2\n    port: 50000\n    counts_per_force: 1e6\n    counts_per_torque: 1e3\n    torque_unit: N-mm\n",
                "rig.yaml");
  EXPECT_EQ(counts.devices.force_plate->counts_per_torque, 1e3);
  EXPECT_EQ(counts.devices.force_plate->torque_unit, "N-mm");
  EXPECT_TRUE(fails_with(parse(head + "    calibration_xml: box.xml\n"), 0, "devices.force_plate.host", "box's address"));
  EXPECT_TRUE(fails_with(parse(head + "    host: h\n"), 0, "devices.force_plate.counts_per_force", "counts per unit are needed"));
  EXPECT_TRUE(fails_with(parse(head + "    host: h\n    calibration_xml: a.xml\n    counts_per_force: 1\n    counts_per_torque: 1\n"), 0,
                         "devices.force_plate.calibration_xml", "not both"));
  EXPECT_TRUE(fails_with(parse(head + "    host: h\n    counts_per_force: 1e6\n"), 0, "devices.force_plate.counts_per_torque",
                         "give both"));
  EXPECT_TRUE(fails_with(parse(head + "    host: h\n    calibration_xml: a.xml\n    port: 0\n"), 0, "devices.force_plate.port",
                         "1..65535"));
  EXPECT_TRUE(fails_with(parse(head + "    host: h\n    calibration_xml: a.xml\n    interface: can0\n"), 0, "devices.force_plate.interface",
                         "UDP"));
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {protocol: ati_netcanoem, host: h}\n"), 0, "devices.force_plate.host",
                         "only the ati_netft_rdt protocol"));
  EXPECT_TRUE(fails_with(parse(kRig + "devices:\n  force_plate: {protocol: ati_netft}\n"), 0, "devices.force_plate.protocol",
                         "'ati_netft_rdt'"));
}
