// An independent check of a hil MCAP recording: @mcap/core (the MCAP project's own TypeScript
// reader) reads every record with CRC validation, both as a stream and through the summary's
// indexes; @foxglove/rosmsg parses each ros2msg schema and @foxglove/rosmsg2-serialization decodes
// every CDR message, which is compared with the run's samples.csv.
//
// node check_mcap.mjs FILE.mcap SAMPLES.csv [--tf child,child,...] [--min-status N] [--joints N]
//                      [--edge parent,child] [--world NAME]
// --edge: the moving transform expected on /tf with every sample (without it: no /tf channel); it
// is composed here with /tf_static's chain to the root and compared with the pose in samples.csv.
import { readFileSync } from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const [file, samplesCsv, ...rest] = process.argv.slice(2);
if (!file || !samplesCsv) {
  console.error("usage: node check_mcap.mjs FILE.mcap SAMPLES.csv [--tf a,b] [--min-status N] [--joints N]");
  process.exit(2);
}
const opt = { tf: null, minStatus: 0, joints: null, edge: null, world: "world" };
for (let i = 0; i < rest.length; i += 2) {
  if (rest[i] === "--tf") opt.tf = rest[i + 1].split(",");
  else if (rest[i] === "--min-status") opt.minStatus = Number(rest[i + 1]);
  else if (rest[i] === "--joints") opt.joints = Number(rest[i + 1]);
  else if (rest[i] === "--edge") opt.edge = rest[i + 1].split(",");
  else if (rest[i] === "--world") opt.world = rest[i + 1];
  else throw new Error(`unknown option ${rest[i]}`);
}

let failures = 0;
function check(cond, what) {
  if (!cond) {
    failures++;
    console.error(`FAIL: ${what}`);
  }
}
function near(a, b) {
  return Math.abs(a - b) <= 1e-12 * Math.max(1, Math.abs(a), Math.abs(b));
}

// samples.csv: header, then rows (comment lines skipped).
const lines = readFileSync(samplesCsv, "utf8").split("\n").filter((l) => l && !l.startsWith("#"));
const cols = lines[0].split(",");
const rows = lines.slice(1).map((l) => {
  const cells = l.split(",");
  const r = {};
  cols.forEach((c, i) => (r[c] = Number(cells[i])));
  return r;
});
const jointCols = cols.filter((c) => /^j\d+$/.test(c));

const bytes = new Uint8Array(readFileSync(file));
const decompressHandlers = await loadDecompressHandlers();

// 1. Stream reader: every record in file order, CRCs validated.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true, includeChunks: true });
stream.append(bytes);
const kinds = new Map();
const streamMessages = [];
for (let rec; (rec = stream.nextRecord()); ) {
  kinds.set(rec.type, (kinds.get(rec.type) ?? 0) + 1);
  if (rec.type === "Message") streamMessages.push(rec);
}
check(stream.done(), "stream reader did not reach the footer's end");
for (const k of ["Header", "Schema", "Channel", "Message", "Chunk", "MessageIndex", "ChunkIndex", "Statistics",
                 "SummaryOffset", "DataEnd", "Footer"])
  check((kinds.get(k) ?? 0) > 0, `no ${k} record`);

// 2. Indexed reader: summary (its CRC), chunk indexes, chunks (their CRCs), message indexes.
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
check(reader.header.profile === "ros2", `profile '${reader.header.profile}'`);
check(reader.dataSectionCrc !== undefined && reader.dataSectionCrc !== 0, "no data-section CRC");
const topics = new Map([...reader.channelsById.values()].map((c) => [c.topic, c]));
const expected = {
  "/hil/wrench": "geometry_msgs/msg/WrenchStamped",
  "/hil/pose": "geometry_msgs/msg/PoseStamped",
  "/hil/joint_states": "sensor_msgs/msg/JointState",
  "/hil/pose_wrench": "hil_msgs/msg/PoseWrenchSample",
  "/hil/device_status": "hil_msgs/msg/DeviceStatus",
  "/tf_static": "tf2_msgs/msg/TFMessage",
};
if (opt.edge) expected["/tf"] = "tf2_msgs/msg/TFMessage";
else check(!topics.has("/tf"), "a /tf channel where none was asked for");
const decoders = new Map();
for (const [topic, type] of Object.entries(expected)) {
  const ch = topics.get(topic);
  check(ch !== undefined, `no channel ${topic}`);
  if (!ch) continue;
  const schema = reader.schemasById.get(ch.schemaId);
  check(ch.messageEncoding === "cdr", `${topic}: message encoding ${ch.messageEncoding}`);
  check(schema && schema.name === type && schema.encoding === "ros2msg", `${topic}: schema ${schema?.name} ${schema?.encoding}`);
  const text = new TextDecoder().decode(schema.data);
  decoders.set(ch.id, { topic, reader: new MessageReader(parse(text, { ros2: true })) });
}

const byTopic = new Map(Object.keys(expected).map((t) => [t, []]));
let indexed = 0;
for await (const m of reader.readMessages({ validateCrcs: true })) {
  indexed++;
  const d = decoders.get(m.channelId);
  if (!d) {
    check(false, `a message on channel ${m.channelId} (${reader.channelsById.get(m.channelId)?.topic}), not one this check expects`);
    continue;
  }
  const value = d.reader.readMessage(m.data);
  check(!d.reader.lastReadHadTrailingBytes(), `${d.topic}: trailing bytes after a message (schema and payload disagree)`);
  byTopic.get(d.topic).push({ log: m.logTime, pub: m.publishTime, value });
}
const stats = reader.statistics;
check(stats && Number(stats.messageCount) === indexed, `statistics say ${stats?.messageCount} messages, read ${indexed}`);
check(streamMessages.length === indexed, `stream reader ${streamMessages.length} messages, indexed ${indexed}`);

// 3. Values against samples.csv.
const stampNs = (t) => BigInt(t.sec) * 1000000000n + BigInt(t.nanosec);
const n = rows.length;
const pw = byTopic.get("/hil/pose_wrench"), wr = byTopic.get("/hil/wrench"), po = byTopic.get("/hil/pose");
check(pw.length === n, `/hil/pose_wrench: ${pw.length} messages, samples.csv has ${n} rows`);
check(wr.length === n, `/hil/wrench: ${wr.length} messages, samples.csv has ${n} rows`);
check(po.length === n, `/hil/pose: ${po.length} messages, samples.csv has ${n} rows`);
const t0 = pw.length ? pw[0].log - BigInt(Math.round(rows[0].t * 1e9)) : 0n;  // the run's start
for (let i = 0; i < Math.min(n, pw.length, wr.length, po.length); i++) {
  const r = rows[i], s = pw[i].value, w = wr[i].value, p = po[i].value;
  const where = `sample ${i} (t=${r.t})`;
  check(Number(s.sample_index) === i, `${where}: sample_index ${s.sample_index}`);
  check(near(s.t_s, r.t), `${where}: t_s ${s.t_s}`);
  check(near(s.pose_world_ee.position.x, r.px) && near(s.pose_world_ee.position.z, r.pz), `${where}: px/pz`);
  check(near(s.pose_world_ee.orientation.w, r.qw) && near(s.pose_world_ee.orientation.x, r.qx), `${where}: qw/qx`);
  check(near(s.wrench_fp.force.x, r.fx) && near(s.wrench_fp.force.z, r.fz) && near(s.wrench_fp.torque.y, r.my), `${where}: fx/fz/my`);
  check(near(s.twist_world_ee.linear.z, r.vz), `${where}: vz`);
  check(near(w.wrench.force.x, r.fx) && near(w.wrench.torque.z, r.mz), `${where}: WrenchStamped fx/mz`);
  check(w.header.frame_id === "force_plate", `${where}: wrench frame '${w.header.frame_id}'`);
  check(stampNs(w.header.stamp) === wr[i].log && wr[i].log === wr[i].pub, `${where}: wrench stamp, log and publish time differ`);
  check(near(p.pose.position.y, r.py) && p.header.frame_id === opt.world, `${where}: PoseStamped (frame '${p.header.frame_id}')`);
  const tNs = t0 + BigInt(Math.round(r.t * 1e9));
  check(pw[i].log - tNs <= 1n && tNs - pw[i].log <= 1n, `${where}: log time ${pw[i].log} is not start + t (${tNs})`);
  jointCols.forEach((c, k) => check(near(s.joint_positions_rad[k], r[c]), `${where}: ${c}`));
}
const js = byTopic.get("/hil/joint_states");
if (jointCols.length > 0) {
  check(js.length === n, `/hil/joint_states: ${js.length} messages for ${n} rows with joints`);
  for (let i = 0; i < Math.min(n, js.length); i++) {
    check(js[i].value.name.length === jointCols.length, `joint_states ${i}: ${js[i].value.name.length} names`);
    jointCols.forEach((c, k) => check(near(js[i].value.position[k], rows[i][c]), `joint_states ${i}: ${c}`));
  }
} else {
  check(js.length === 0, `/hil/joint_states: ${js.length} messages for a run without joints`);
}
if (opt.joints !== null) check(jointCols.length === opt.joints, `samples.csv has ${jointCols.length} joint columns, expected ${opt.joints}`);

const tf = byTopic.get("/tf_static");
if (opt.tf) {
  check(tf.length === 1, `/tf_static: ${tf.length} messages, expected 1`);
  const children = tf.length ? tf[0].value.transforms.map((x) => x.child_frame_id) : [];
  check(JSON.stringify(children) === JSON.stringify(opt.tf), `/tf_static frames ${children} (expected ${opt.tf})`);
  for (const x of tf[0]?.value.transforms ?? []) {
    const q = x.transform.rotation;
    check(Math.abs(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w - 1) < 1e-9, `/tf_static ${x.child_frame_id}: quaternion not unit`);
  }
} else {
  check(tf.length === 0, `/tf_static: ${tf.length} messages without a rig`);
}
// Rigid transforms as {p: [x,y,z], q: [w,x,y,z]}: compose, and from a ROS Transform.
const qmul = (a, b) => [a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]];
const rot = (q, v) => qmul(qmul(q, [0, ...v]), [q[0], -q[1], -q[2], -q[3]]).slice(1);
const compose = (A, B) => ({ p: rot(A.q, B.p).map((x, k) => x + A.p[k]), q: qmul(A.q, B.q) });
const fromRos = (t) => ({ p: [t.translation.x, t.translation.y, t.translation.z], q: [t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z] });
const identity = { p: [0, 0, 0], q: [1, 0, 0, 0] };

const moving = byTopic.get("/tf") ?? [];
if (opt.edge) {
  // One tree: every static frame has one parent and reaches the root through /tf_static, or through
  // the moving edge's child (the frames carried by the end effector).
  const parentOf = new Map();
  for (const x of tf[0]?.value.transforms ?? []) {
    check(!parentOf.has(x.child_frame_id), `/tf_static: ${x.child_frame_id} has two parents`);
    parentOf.set(x.child_frame_id, { parent: x.header.frame_id, T: fromRos(x.transform) });
  }
  const [edgeParent, edgeChild] = opt.edge;
  check(!parentOf.has(edgeChild), `${edgeChild} has a parent on /tf_static and on /tf`);
  const chainToRoot = (frame) => {  // T_root_frame through /tf_static, or null
    let T = identity;
    for (let hops = 0; frame !== opt.world; hops++) {
      const e = parentOf.get(frame);
      if (!e || hops > parentOf.size) return null;
      T = compose(e.T, T);
      frame = e.parent;
    }
    return T;
  };
  for (const child of parentOf.keys()) {
    let f = child;
    while (parentOf.has(f) && f !== edgeChild) f = parentOf.get(f).parent;
    check(f === opt.world || f === edgeChild, `/tf_static: ${child} does not reach ${opt.world} (stops at ${f})`);
  }
  const T_world_parent = chainToRoot(edgeParent);
  check(T_world_parent !== null, `/tf parent ${edgeParent} does not reach ${opt.world} through /tf_static`);
  check(moving.length === n, `/tf: ${moving.length} messages, samples.csv has ${n} rows`);
  for (let i = 0; i < Math.min(n, moving.length, po.length) && T_world_parent; i++) {
    const where = `/tf ${i} (t=${rows[i].t})`, m = moving[i].value;
    check(m.transforms.length === 1, `${where}: ${m.transforms.length} transforms`);
    const x = m.transforms[0];
    check(x.header.frame_id === edgeParent && x.child_frame_id === edgeChild, `${where}: ${x.header.frame_id} -> ${x.child_frame_id}`);
    check(stampNs(x.header.stamp) === moving[i].log && moving[i].log === po[i].log, `${where}: stamp differs from the pose's`);
    const T = compose(T_world_parent, fromRos(x.transform)), r = rows[i];
    const want = { p: [r.px, r.py, r.pz], q: [r.qw, r.qx, r.qy, r.qz] };
    const dq = Math.abs(T.q.reduce((acc, v, k) => acc + v * want.q[k], 0));  // |<q, q'>| = 1 for one rotation
    check(T.p.every((v, k) => Math.abs(v - want.p[k]) < 1e-9) && Math.abs(dq - 1) < 1e-9,
          `${where}: ${opt.world} -> ${edgeChild} through the tree is ${JSON.stringify(T)}, samples.csv has ${JSON.stringify(want)}`);
  }
}

const status = byTopic.get("/hil/device_status");
check(status.length >= opt.minStatus, `/hil/device_status: ${status.length} messages, expected at least ${opt.minStatus}`);
for (const s of status) check(["force_plate", "robot"].includes(s.value.device), `device_status device '${s.value.device}'`);

const counts = [...byTopic].map(([t, v]) => `${t} ${v.length}`).join(", ");
if (failures > 0) {
  console.error(`${file}: ${failures} check(s) failed (${counts})`);
  process.exit(1);
}
console.log(`${file}: OK, ${indexed} messages (${counts}), records: ${[...kinds].map(([k, v]) => `${k} ${v}`).join(", ")}`);
