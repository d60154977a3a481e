#!/usr/bin/env python3
"""The ROS 2 side of hil's bus types cannot drift from the IDL that hil publishes with:

- every struct of idl/msg/hil_msgs.idl has a .msg file in ros/hil_msgs/msg/ with the same fields,
  in the same order, of the same types, and the same constants (a module-level constant of the IDL
  belongs to the struct declared next after it; ROS 2's own `X_Constants` modules to X), and no
  .msg file is without its struct;
- ros/hil_msgs/package.xml (format 3, ament_cmake, rosidl generators, member of
  rosidl_interface_packages) depends on every package the .msg files use, and its CMakeLists.txt
  generates every .msg file with those dependencies;
- the standard ROS 2 types hil carries (idl/msg/{builtin_interfaces,std_msgs,geometry_msgs,
  sensor_msgs,tf2_msgs,diagnostic_msgs,rosgraph_msgs}.idl) are field for field the ROS 2 definitions below
  (default values aside: they never reach the wire).

No ROS 2 is needed: the IDL subset hil uses and the .msg grammar are parsed here.
Usage: test_msgs_match_idl.py SOURCE_DIR
"""
import os
import re
import shutil
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

SRC = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
IDL_DIR = os.path.join(SRC, "idl", "msg")
PKG_DIR = os.path.join(SRC, "ros", "hil_msgs")

# IDL primitive -> .msg primitive (ROS 2's mapping, design article "IDL - Interface Definition
# and Language Mapping"). uint8/int8 are IDL 4 types fastddsgen accepts; byte is octet.
IDL_TO_MSG = {
    "boolean": "bool", "octet": "byte", "char": "char", "int8": "int8", "uint8": "uint8",
    "int16": "int16", "uint16": "uint16", "int32": "int32", "uint32": "uint32", "int64": "int64",
    "uint64": "uint64", "float": "float32", "double": "float64", "string": "string", "wstring": "wstring",
    "short": "int16", "unsigned short": "uint16", "long": "int32", "unsigned long": "uint32",
    "long long": "int64", "unsigned long long": "uint64",
}
MSG_PRIMITIVES = {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64",
                  "uint64", "float32", "float64", "string", "wstring"}

# The ROS 2 definitions (rolling/humble .msg files, comments and defaults left out).
ROS2_REFERENCE = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "Point position\nQuaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\nPose pose",
    "geometry_msgs/Twist": "Vector3 linear\nVector3 angular",
    "geometry_msgs/Wrench": "Vector3 force\nVector3 torque",
    "geometry_msgs/WrenchStamped": "std_msgs/Header header\nWrench wrench",
    "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation",
    "geometry_msgs/TransformStamped": "std_msgs/Header header\nstring child_frame_id\nTransform transform",
    "sensor_msgs/JointState": "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort",
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms",
    "rosgraph_msgs/Clock": "builtin_interfaces/Time clock",
    "diagnostic_msgs/KeyValue": "string key\nstring value",
    "diagnostic_msgs/DiagnosticStatus": "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
                                        "byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values",
    "diagnostic_msgs/DiagnosticArray": "std_msgs/Header header\nDiagnosticStatus[] status",
}


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def write(path, text):
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


class Definition:
    """One message: fields [(type, name)] in order and constants {name: (type, value)}."""

    def __init__(self):
        self.fields = []
        self.constants = {}

    def __repr__(self):
        return f"fields={self.fields} constants={self.constants}"


# ---------------------------------------------------------------------------------------------
# IDL (the subset hil writes: modules, structs, consts, sequences, arrays, bounded strings)

def strip_idl_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def idl_tokens(text):
    text = "\n".join(l for l in text.splitlines() if not l.lstrip().startswith("#"))  # preprocessor
    return re.findall(r"::|[A-Za-z_][A-Za-z0-9_]*|-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|\"[^\"]*\"|'[^']*'|[{}<>;,\[\]=()]", strip_idl_comments(text))


def msg_type_from_idl(idl_type, package):
    """'geometry_msgs::msg::Pose' -> 'geometry_msgs/Pose'; 'double' -> 'float64'; bare names are
    the package's own."""
    if idl_type in IDL_TO_MSG:
        return IDL_TO_MSG[idl_type]
    m = re.fullmatch(r"(string|wstring)<(\d+)>", idl_type)
    if m:
        return f"{m.group(1)}<={m.group(2)}"
    parts = idl_type.split("::")
    if len(parts) == 3 and parts[1] == "msg":
        return f"{parts[0]}/{parts[2]}"
    if len(parts) == 1:
        return f"{package}/{parts[0]}"
    raise ValueError(f"unsupported IDL type '{idl_type}'")


def parse_idl(path):
    """{'pkg/Name': Definition} for every struct of the file, constants attached (see module doc)."""
    toks = idl_tokens(read(path))
    defs = {}
    modules = []
    pending_constants = {}  # module-level constants waiting for the next struct
    i = 0

    def read_type(i):
        """A type expression starting at toks[i] -> (type string for msg, next index)."""
        if toks[i] == "sequence":
            assert toks[i + 1] == "<", f"{path}: sequence without <"
            inner, j = read_type(i + 2)
            bound = None
            if toks[j] == ",":
                bound, j = toks[j + 1], j + 2
            assert toks[j] == ">", f"{path}: sequence not closed at '{toks[j]}'"
            return (f"{inner}[<={bound}]" if bound else f"{inner}[]"), j + 1
        if toks[i] == "unsigned":
            if toks[i + 1] == "long" and toks[i + 2] == "long":
                return IDL_TO_MSG["unsigned long long"], i + 3
            return IDL_TO_MSG["unsigned " + toks[i + 1]], i + 2
        if toks[i] == "long" and toks[i + 1] == "long":
            return IDL_TO_MSG["long long"], i + 2
        if toks[i] in ("string", "wstring") and toks[i + 1] == "<":
            return f"{toks[i]}<={toks[i + 2]}", i + 4
        name = toks[i]
        j = i + 1
        while j < len(toks) and toks[j] == "::":
            name += "::" + toks[j + 1]
            j += 2
        return msg_type_from_idl(name, package()), j

    def package():
        return modules[0] if modules else ""

    while i < len(toks):
        t = toks[i]
        if t == "module":
            modules.append(toks[i + 1])
            assert toks[i + 2] == "{", f"{path}: module {toks[i + 1]} without a body"
            i += 3
        elif t == "}":
            # end of a module (structs consume their own braces)
            assert toks[i + 1] == ";", f"{path}: '}}' without ';'"
            modules.pop()
            i += 2
        elif t == "const":
            ctype, j = read_type(i + 1)
            name, eq, value = toks[j], toks[j + 1], toks[j + 2]
            assert eq == "=" and toks[j + 3] == ";", f"{path}: malformed const {name}"
            owner = modules[-1][: -len("_Constants")] if modules[-1].endswith("_Constants") else None
            if owner:
                key = f"{package()}/{owner}"
                defs.setdefault(key, Definition()).constants[name] = (ctype, value)
            else:
                pending_constants[name] = (ctype, value)
            i = j + 4
        elif t == "struct":
            name = toks[i + 1]
            assert toks[i + 2] == "{", f"{path}: struct {name} without a body"
            d = defs.setdefault(f"{package()}/{name}", Definition())
            d.constants.update(pending_constants)
            pending_constants = {}
            j = i + 3
            while toks[j] != "}":
                ftype, j = read_type(j)
                fname = toks[j]
                j += 1
                while toks[j] == "[":  # fixed-size array
                    ftype = f"{ftype}[{toks[j + 1]}]"
                    j += 3
                assert toks[j] == ";", f"{path}: struct {name}: field {fname} not ended by ';' (found '{toks[j]}')"
                d.fields.append((ftype, fname))
                j += 1
            assert toks[j + 1] == ";", f"{path}: struct {name} not ended by '}};'"
            i = j + 2
        elif t in ("typedef", "enum", "union"):
            raise AssertionError(f"{path}: '{t}' is not used by hil's IDL and not parsed here")
        else:
            raise AssertionError(f"{path}: unexpected '{t}'")
    assert not pending_constants, f"{path}: constants {sorted(pending_constants)} precede no struct"
    return defs


# ---------------------------------------------------------------------------------------------
# .msg

def msg_type(raw, package, where):
    m = re.fullmatch(r"([A-Za-z0-9_/]+?)(<=\d+)?(\[(?:<=)?\d*\])?", raw)
    if not m:
        raise AssertionError(f"{where}: cannot read the type '{raw}'")
    base, bound, array = m.group(1), m.group(2) or "", m.group(3) or ""
    if base in MSG_PRIMITIVES:
        return base + bound + array
    if base == "Header":  # ROS 1 shorthand, still accepted by rosidl
        base = "std_msgs/Header"
    if "/" not in base:
        base = f"{package}/{base}"
    return base + bound + array


def parse_msg_text(text, package, where):
    d = Definition()
    for n, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.fullmatch(r"(\S+)\s+([A-Z][A-Z0-9_]*)\s*=\s*(\S.*)", line)
        if m:
            d.constants[m.group(2)] = (msg_type(m.group(1), package, f"{where}:{n}"), m.group(3).strip())
            continue
        m = re.fullmatch(r"(\S+)\s+([a-z][a-z0-9_]*)(\s+\S.*)?", line)
        if not m:
            raise AssertionError(f"{where}:{n}: neither a field nor a constant: '{line}'")
        d.fields.append((msg_type(m.group(1), package, f"{where}:{n}"), m.group(2)))  # defaults are not wire
    return d


def packages_used(defs, own):
    used = set()
    for d in defs.values():
        for t, _ in d.fields:
            if "/" in t:
                pkg = t.split("/")[0]
                if pkg != own:
                    used.add(pkg)
    return used


def compare(expected, actual, where, la="IDL", lb=".msg"):
    """Differences between two Definitions, as readable lines (la and lb name the two sides)."""
    problems = []
    if expected.fields != actual.fields:
        width = max(len(expected.fields), len(actual.fields))
        for k in range(width):
            e = expected.fields[k] if k < len(expected.fields) else None
            a = actual.fields[k] if k < len(actual.fields) else None
            if e != a:
                problems.append(f"{where}: field {k + 1}: {la} has {e and ' '.join(e)}, {lb} has {a and ' '.join(a)}")
    for name in sorted(set(expected.constants) | set(actual.constants)):
        e, a = expected.constants.get(name), actual.constants.get(name)
        if e != a:
            problems.append(f"{where}: constant {name}: {la} has {e}, {lb} has {a}")
    return problems


def check_package(pkg_dir):
    """Every problem of a ROS 2 interface package against the IDL: a list of lines."""
    problems = []
    idl = parse_idl(os.path.join(IDL_DIR, "hil_msgs.idl"))
    msg_dir = os.path.join(pkg_dir, "msg")
    msgs = {}
    for f in sorted(os.listdir(msg_dir)):
        if f.endswith(".msg"):
            path = os.path.join(msg_dir, f)
            msgs["hil_msgs/" + f[:-4]] = parse_msg_text(read(path), "hil_msgs", path)
    for name in sorted(set(idl) - set(msgs)):
        problems.append(f"{name}: in idl/msg/hil_msgs.idl but no ros/hil_msgs/msg/{name.split('/')[1]}.msg")
    for name in sorted(set(msgs) - set(idl)):
        problems.append(f"ros/hil_msgs/msg/{name.split('/')[1]}.msg: no struct {name.split('/')[1]} in idl/msg/hil_msgs.idl")
    for name in sorted(set(idl) & set(msgs)):
        problems += compare(idl[name], msgs[name], name)

    used = packages_used(msgs, "hil_msgs")
    # package.xml
    xml_path = os.path.join(pkg_dir, "package.xml")
    root = ET.parse(xml_path).getroot()
    if root.get("format") != "3":
        problems.append(f"{xml_path}: <package format=\"3\"> expected")
    if (root.findtext("name") or "").strip() != "hil_msgs":
        problems.append(f"{xml_path}: <name>hil_msgs</name> expected")

    def texts(tag):
        return {(e.text or "").strip() for e in root.findall(tag)}

    for tag, value in (("buildtool_depend", "ament_cmake"), ("buildtool_depend", "rosidl_default_generators"),
                       ("exec_depend", "rosidl_default_runtime"), ("member_of_group", "rosidl_interface_packages")):
        if value not in texts(tag):
            problems.append(f"{xml_path}: <{tag}>{value}</{tag}> missing")
    if (root.findtext("export/build_type") or "").strip() != "ament_cmake":
        problems.append(f"{xml_path}: <export><build_type>ament_cmake</build_type></export> missing")
    depends = texts("depend")
    for pkg in sorted(used):
        if pkg not in depends and not (pkg in texts("build_depend") and pkg in texts("exec_depend")):
            problems.append(f"{xml_path}: the .msg files use {pkg} but it is not a <depend>")

    # CMakeLists.txt
    cm_path = os.path.join(pkg_dir, "CMakeLists.txt")
    cm = re.sub(r"#[^\n]*", "", read(cm_path))
    m = re.search(r"rosidl_generate_interfaces\s*\(\s*\$\{PROJECT_NAME\}(.*?)\)", cm, flags=re.S)
    if not m:
        problems.append(f"{cm_path}: no rosidl_generate_interfaces(${{PROJECT_NAME}} ...)")
    else:
        body = m.group(1)
        listed = set(re.findall(r"\"?msg/([A-Za-z0-9_]+)\.msg\"?", body))
        files = {n.split("/")[1] for n in msgs}
        for f in sorted(files - listed):
            problems.append(f"{cm_path}: msg/{f}.msg is not in rosidl_generate_interfaces")
        for f in sorted(listed - files):
            problems.append(f"{cm_path}: rosidl_generate_interfaces lists msg/{f}.msg, which does not exist")
        dm = re.search(r"DEPENDENCIES\s+([^)]*)", body)
        deps = set(dm.group(1).split()) if dm else set()
        for pkg in sorted(used - deps):
            problems.append(f"{cm_path}: rosidl_generate_interfaces lacks DEPENDENCIES {pkg}")
    for pkg in sorted(used | {"ament_cmake", "rosidl_default_generators"}):
        if not re.search(r"find_package\s*\(\s*" + re.escape(pkg) + r"\s+REQUIRED", cm):
            problems.append(f"{cm_path}: find_package({pkg} REQUIRED) missing")
    return problems


class HilMsgsPackage(unittest.TestCase):
    def test_package_matches_idl(self):
        problems = check_package(PKG_DIR)
        self.assertEqual(problems, [], "\n" + "\n".join(problems))

    def test_every_struct_checked(self):
        # The parser must see the structs and constants that are there (an empty parse passes nothing).
        idl = parse_idl(os.path.join(IDL_DIR, "hil_msgs.idl"))
        self.assertIn("hil_msgs/PoseWrenchSample", idl)
        self.assertIn(("float64", "t_s"), idl["hil_msgs/PoseWrenchSample"].fields)
        self.assertEqual(idl["hil_msgs/PoseWrenchSample"].constants["QUALITY_GAP_BEFORE"], ("uint32", "32"))
        self.assertEqual(idl["hil_msgs/DeviceStatus"].constants["DEVICE_DISCONNECTED"], ("uint8", "3"))
        self.assertEqual(idl["hil_msgs/StiffnessEstimate"].fields[3], ("hil_msgs/StiffnessParameter[]", "parameters"))

    def test_drift_is_caught(self):
        """A copy of the package with one change of each kind must fail, naming it."""
        cases = [
            ("msg/PoseWrenchSample.msg", "float64 t_s", "float32 t_s", "field 3"),
            ("msg/PoseWrenchSample.msg", "uint64 wrench_seq                    # sequence number of the newest wrench frame used\n"
                                         "uint64 pose_seq", "uint64 pose_seq\nuint64 wrench_seq", "field 8"),
            ("msg/DeviceStatus.msg", "uint8 DEVICE_FAULT=2", "uint8 DEVICE_FAULT=4", "constant DEVICE_FAULT"),
            ("msg/ContactEstimate.msg", "float64 relative_force_error", "", "field 12"),
            ("msg/StiffnessParameter.msg", "string name", "string label", "field 1"),
            ("package.xml", "<depend>geometry_msgs</depend>", "", "geometry_msgs but it is not a <depend>"),
            ("CMakeLists.txt", '"msg/ContactEstimate.msg"', "", "msg/ContactEstimate.msg is not in rosidl_generate_interfaces"),
            ("CMakeLists.txt", "DEPENDENCIES builtin_interfaces geometry_msgs std_msgs", "DEPENDENCIES builtin_interfaces std_msgs",
             "lacks DEPENDENCIES geometry_msgs"),
        ]
        for rel, old, new, needle in cases:
            with self.subTest(file=rel, change=needle), tempfile.TemporaryDirectory() as tmp:
                copy = os.path.join(tmp, "hil_msgs")
                shutil.copytree(PKG_DIR, copy)
                path = os.path.join(copy, rel)
                text = read(path)
                self.assertIn(old, text, f"the test's edit no longer applies to {rel}")
                write(path, text.replace(old, new, 1))
                problems = check_package(copy)
                self.assertTrue(any(needle in p for p in problems), f"{needle!r} not in {problems}")
        # A .msg without a struct.
        with tempfile.TemporaryDirectory() as tmp:
            copy = os.path.join(tmp, "hil_msgs")
            shutil.copytree(PKG_DIR, copy)
            write(os.path.join(copy, "msg", "Extra.msg"), "float64 x\n")
            self.assertTrue(any("Extra.msg: no struct Extra" in p for p in check_package(copy)))


class StandardTypes(unittest.TestCase):
    def test_standard_types_are_ros2s(self):
        idl = {}
        for f in ("builtin_interfaces", "std_msgs", "geometry_msgs", "sensor_msgs", "tf2_msgs", "diagnostic_msgs", "rosgraph_msgs"):
            idl.update(parse_idl(os.path.join(IDL_DIR, f + ".idl")))
        problems = []
        for name, text in ROS2_REFERENCE.items():
            if name not in idl:
                problems.append(f"{name}: not in idl/msg")
                continue
            problems += compare(parse_msg_text(text, name.split("/")[0], name), idl[name], name, "ROS 2", "idl/msg")
        for name in sorted(set(idl) - set(ROS2_REFERENCE)):
            problems.append(f"{name}: in idl/msg but without a ROS 2 reference in this test")
        self.assertEqual(problems, [], "\n" + "\n".join(problems))


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
