// An independent reader of a MAVLink board's serial stream for the tests: reads FILE (the raw
// bytes the flight controller's end of the link received) with node-mavlink, the splitter
// checking every frame's CRC with the common message set's CRC extras, and decodes each message
// with that set's own definitions. Prints JSON: the messages in order (their name, sender and
// fields) and the frames the splitter found invalid.
//
//   node mavlink-read.mjs FILE
import { createReadStream } from "node:fs";
import { MavLinkPacketSplitter, MavLinkPacketParser, minimal, common } from "node-mavlink";

const [file] = process.argv.slice(2);
if (!file) {
  console.error("usage: node mavlink-read.mjs FILE");
  process.exit(2);
}
const registry = { ...minimal.REGISTRY, ...common.REGISTRY };
let crcErrors = 0;
const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => crcErrors++ });
const reader = createReadStream(file).pipe(splitter).pipe(new MavLinkPacketParser());

// Fields as JSON: bigints as numbers, strings cut at their first NUL.
const plain = (value) => {
  if (typeof value === "bigint") return Number(value);
  if (typeof value === "string") return value.split("\0")[0];
  if (Array.isArray(value)) return value.map(plain);
  return value;
};

const messages = [];
let unknown = 0;
reader.on("data", (packet) => {
  const clazz = registry[packet.header.msgid];
  if (!clazz) {
    unknown++;
    return;
  }
  const data = packet.protocol.data(packet.payload, clazz);
  const fields = {};
  for (const field of clazz.FIELDS) fields[field.source] = plain(data[field.name]);
  messages.push({ name: clazz.MSG_NAME, msgid: packet.header.msgid, seq: packet.header.seq,
    sysid: packet.header.sysid, compid: packet.header.compid, version: packet.header.magic,
    fields });
});
reader.on("end", () => {
  console.log(JSON.stringify({ messages, unknown, crc_errors: crcErrors,
    invalid: splitter.invalidPackages }));
});
reader.on("error", (e) => {
  console.error(`mavlink-read: ${e.message}`);
  process.exit(1);
});
