// A ros2 bag of standard topics as a lab's robot and sensor drivers would record it, written
// without hil: @mcap/core's writer, @foxglove/rosmsg2-serialization's CDR, the message definitions
// written out here. The motion and forces come from a run's samples.csv (50 Hz), sampled as the
// devices would be: the wrench at 1 kHz (linear between rows), the pose and the joints at 125 Hz.
//
// node make_bag.mjs SAMPLES.csv START_NS BAG_FOLDER [--bad-quaternion]
//   -> BAG_FOLDER/metadata.yaml, BAG_FOLDER/bag_0.mcap; topics /ft/wrench (frame force_plate),
//      /robot/ee_pose (frame world), /joint_states (joints a1..a6).
import { mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";

const [csv, startArg, folder, flag] = process.argv.slice(2);
const badQuaternion = flag === "--bad-quaternion";  // pose 100's orientation not unit: a bad input
const start = BigInt(startArg);

const SEP = "\n================================================================================\n";
const TIME = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
const HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id";
const VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z";
const types = {
  "geometry_msgs/msg/WrenchStamped": ["std_msgs/Header header\ngeometry_msgs/Wrench wrench", HEADER, TIME,
    "MSG: geometry_msgs/Wrench\nVector3 force\nVector3 torque", VECTOR3].join(SEP),
  "geometry_msgs/msg/PoseStamped": ["std_msgs/Header header\ngeometry_msgs/Pose pose", HEADER, TIME,
    "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation", "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z",
    "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1"].join(SEP),
  "sensor_msgs/msg/JointState": ["std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort",
    HEADER, TIME].join(SEP),
};

const lines = readFileSync(csv, "utf8").split("\n").filter((l) => l && !l.startsWith("#"));
const cols = lines[0].split(",");
const rows = lines.slice(1).map((l) => Object.fromEntries(l.split(",").map((v, i) => [cols[i], Number(v)])));
const tEnd = rows[rows.length - 1].t;
// The row pair around t and the weight of the later one.
function at(t, keys) {
  let i = Math.min(rows.length - 2, Math.max(0, Math.floor(t / (rows[1].t - rows[0].t))));
  while (i > 0 && rows[i].t > t) i--;
  while (i < rows.length - 2 && rows[i + 1].t < t) i++;
  const a = rows[i], b = rows[i + 1], u = Math.min(1, Math.max(0, (t - a.t) / (b.t - a.t)));
  return Object.fromEntries(keys.map((k) => [k, a[k] + u * (b[k] - a[k])]));
}
const stampOf = (ns) => ({ sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) });

const out = [];
let pos = 0n;
const writer = new McapWriter({
  writable: { position: () => pos, write: async (buf) => { out.push(Buffer.from(buf)); pos += BigInt(buf.byteLength); } },
  useStatistics: true, useSummaryOffsets: true, useChunks: true, chunkSize: 256 * 1024,
});
await writer.start({ profile: "ros2", library: "hil-test make_bag.mjs" });
const channel = {}, cdr = {};
const add = async (topic, type) => {
  const schemaId = await writer.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode(types[type]) });
  channel[topic] = await writer.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() });
  cdr[topic] = new MessageWriter(parse(types[type], { ros2: true }));
};
await add("/ft/wrench", "geometry_msgs/msg/WrenchStamped");
await add("/robot/ee_pose", "geometry_msgs/msg/PoseStamped");
await add("/joint_states", "sensor_msgs/msg/JointState");

// Every message in time order, as a recorder receives them.
const events = [];
for (let k = 0; k * 1e-3 <= tEnd + 1e-12; k++) events.push({ ns: start + BigInt(k) * 1000000n, topic: "/ft/wrench", t: k * 1e-3 });
for (let k = 0; k * 8e-3 <= tEnd + 1e-12; k++) {
  events.push({ ns: start + BigInt(k) * 8000000n, topic: "/robot/ee_pose", t: k * 8e-3 });
  events.push({ ns: start + BigInt(k) * 8000000n, topic: "/joint_states", t: k * 8e-3 });
}
events.sort((a, b) => (a.ns < b.ns ? -1 : a.ns > b.ns ? 1 : 0));
const counts = {};
let seq = 0;
for (const e of events) {
  const header = { stamp: stampOf(e.ns), frame_id: "" };
  let msg;
  if (e.topic === "/ft/wrench") {
    const v = at(e.t, ["fx", "fy", "fz", "mx", "my", "mz"]);
    msg = { header: { ...header, frame_id: "force_plate" }, wrench: { force: { x: v.fx, y: v.fy, z: v.fz }, torque: { x: v.mx, y: v.my, z: v.mz } } };
  } else if (e.topic === "/robot/ee_pose") {
    const v = at(e.t, ["px", "py", "pz", "qw", "qx", "qy", "qz"]);
    const n = Math.hypot(v.qw, v.qx, v.qy, v.qz) / (badQuaternion && counts[e.topic] === 100 ? 2 : 1);
    msg = { header: { ...header, frame_id: "world" }, pose: { position: { x: v.px, y: v.py, z: v.pz },
            orientation: { x: v.qx / n, y: v.qy / n, z: v.qz / n, w: v.qw / n } } };
  } else {
    const q = [1, 2, 3, 4, 5, 6].map((j) => 0.1 * j * Math.sin(2 * Math.PI * 0.2 * e.t + j));
    msg = { header, name: ["a1", "a2", "a3", "a4", "a5", "a6"], position: q, velocity: [], effort: [] };
  }
  await writer.addMessage({ channelId: channel[e.topic], sequence: seq++, logTime: e.ns, publishTime: e.ns, data: cdr[e.topic].writeMessage(msg) });
  counts[e.topic] = (counts[e.topic] ?? 0) + 1;
}
await writer.end();

mkdirSync(folder, { recursive: true });
writeFileSync(`${folder}/bag_0.mcap`, Buffer.concat(out));
const last = events[events.length - 1].ns;
writeFileSync(`${folder}/metadata.yaml`, `rosbag2_bagfile_information:
  version: 5
  storage_identifier: mcap
  duration:
    nanoseconds: ${last - start}
  starting_time:
    nanoseconds_since_epoch: ${start}
  message_count: ${events.length}
  topics_with_message_count:
${Object.entries(counts).map(([t, n]) => `    - topic_metadata:\n        name: ${t}\n        serialization_format: cdr\n        offered_qos_profiles: ""\n      message_count: ${n}`).join("\n")}
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - bag_0.mcap
  files:
    - path: bag_0.mcap
      starting_time:
        nanoseconds_since_epoch: ${start}
      duration:
        nanoseconds: ${last - start}
      message_count: ${events.length}
`);
console.log(Object.entries(counts).map(([t, n]) => `${t} ${n}`).join(", "));
