// An independent reader of Epipole's MCAP recordings for the tests and the main job's check:
// reads FILE with the MCAP project's own TypeScript library (@mcap/core: the stream reader with
// every CRC checked, then the indexed reader through the summary and the chunk and message
// indexes), decodes every message with Foxglove's ROS 2 CDR decoder from the schema the file
// carries, and prints what it found as JSON: the header, the statistics, the attachments, and
// each message in log-time order with its decoded fields (pixel data as a FNV-1a hash and
// samples on a grid of GRID x GRID points).
//
//   node mcap-read.mjs FILE [GRID]
import { readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";
import { decoderOf, describe, setGrid } from "./ros-summary.mjs";

const [file, gridArg] = process.argv.slice(2);
if (!file) {
  console.error("usage: node mcap-read.mjs FILE [GRID]");
  process.exit(2);
}
setGrid(Number(gridArg ?? 8));
const bytes = new Uint8Array(await readFile(file));
const decompressHandlers = {
  zstd: (data, size) => {
    const out = decompress(data, new Uint8Array(Number(size)));
    if (out.byteLength !== Number(size)) throw new Error("zstd: wrong decompressed size");
    return out;
  },
};

// 1. The stream reader: every record in file order, chunks CRC-checked.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const opcodes = {};
let streamMessages = 0;
for (let record; (record = stream.nextRecord()); ) {
  opcodes[record.type] = (opcodes[record.type] ?? 0) + 1;
  if (record.type === "Message") streamMessages++;
}
if (!stream.done()) throw new Error("the stream reader did not reach the end of the file");

// 2. The indexed reader: the summary, the chunk indexes and the message indexes.
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const decoders = new Map();
for (const [id, channel] of reader.channelsById) {
  const schema = reader.schemasById.get(channel.schemaId);
  if (schema.encoding !== "ros2msg" || channel.messageEncoding !== "cdr") {
    throw new Error(`${channel.topic}: ${schema.encoding}/${channel.messageEncoding}`);
  }
  decoders.set(id, { topic: channel.topic, type: schema.name,
    reader: decoderOf(new TextDecoder().decode(schema.data)) });
}

const messages = [];
for await (const message of reader.readMessages({ validateCrcs: true })) {
  const decoder = decoders.get(message.channelId);
  const m = decoder.reader.readMessage(message.data);
  messages.push(describe(decoder.topic, decoder.type, m,
    { sequence: message.sequence, log_time: message.logTime.toString() }));
}
if (messages.length !== streamMessages) {
  throw new Error(`indexed reader: ${messages.length} messages, stream reader: ${streamMessages}`);
}
const attachments = [];
for await (const a of reader.readAttachments({ validateCrcs: true })) {
  attachments.push({ name: a.name, media_type: a.mediaType, text: new TextDecoder().decode(a.data) });
}
const statistics = reader.statistics;
console.log(JSON.stringify({
  profile: reader.header.profile, library: reader.header.library, records: opcodes,
  statistics: statistics && { message_count: Number(statistics.messageCount),
    chunk_count: statistics.chunkCount, channel_count: statistics.channelCount,
    channel_message_counts: Object.fromEntries([...statistics.channelMessageCounts].map(
      ([id, n]) => [reader.channelsById.get(id).topic, Number(n)])) },
  chunk_indexes: reader.chunkIndexes.length, attachments, messages,
}));
