// The independent count of what can be read of a recording: @mcap/core's streaming reader (CRCs
// validated) over the file's bytes, record by record, as far as they go. A file that was not
// closed ends without a Footer: the reader then waits for more bytes (done() stays false).
//
// node count_messages.mjs FILE.mcap   ->   "messages N samples S complete|incomplete"
import { readFileSync } from "node:fs";
import { McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";

const file = process.argv[2];
const stream = new McapStreamReader({ decompressHandlers: await loadDecompressHandlers(), validateCrcs: true });
stream.append(new Uint8Array(readFileSync(file)));
const topics = new Map();
let messages = 0, samples = 0;
try {
  for (let rec; (rec = stream.nextRecord()); ) {
    if (rec.type === "Channel") topics.set(rec.id, rec.topic);
    if (rec.type === "Message") {
      messages++;
      if (topics.get(rec.channelId) === "/hil/pose_wrench") samples++;
    }
  }
} catch (e) {
  console.error(`${file}: stopped: ${e.message}`);
}
console.log(`messages ${messages} samples ${samples} ${stream.done() ? "complete" : "incomplete"}`);
