#!/usr/bin/env node
// Writes an ASL folder (mav0/imu0, cam0, cam1, optional ground truth) as a ROS 2
// recording with Foxglove's libraries (@mcap/core, @foxglove/rosmsg2-serialization;
// chunks compressed by @foxglove/wasm-zstd or lz4js):
// a writer independent of vio's own, for vio's ROS 2 reader tests.
//
// usage: node write_bag.js --asl=DIR --out=FILE [--compression=none|zstd|lz4|unchunked]
//          [--image=mono8|rgb8|bgr8|bgra8|png|jpeg] [--groundtruth=pose|transform|odometry]
//          [--frames=N] [--format=mcap|jsonl]
//   mcap:  an MCAP file, chunks compressed as asked (unchunked: messages outside chunks).
//   jsonl: one JSON object per message {topic, type, t (ns, string), cdr (base64)}, in
//          stamp order, for write_db3.py (rosbag2's sqlite3 layout from python3's sqlite3).
// Raw images are the PNGs decoded here; png and jpeg are CompressedImages of the
// image files (jpeg: the .jpg beside each .png). Topics: /cam0/image_raw,
// /cam1/image_raw, /imu0, /groundtruth (EuRoC's).
"use strict";
const fs = require("fs");
const path = require("path");
const zlib = require("zlib");
const { McapWriter } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageWriter } = require("@foxglove/rosmsg2-serialization");
const definitions = require("./definitions");

function args() {
  const a = { compression: "zstd", image: "mono8", groundtruth: "pose", format: "mcap", frames: "0" };
  for (const arg of process.argv.slice(2)) {
    const m = /^--([a-z]+)=(.*)$/.exec(arg);
    if (!m) throw new Error(`bad argument ${arg}`);
    a[m[1]] = m[2];
  }
  if (!a.asl || !a.out) throw new Error("--asl and --out are required");
  return a;
}

// Rows of an ASL csv file (comment lines skipped), as arrays of strings.
function csv(file) {
  return fs.readFileSync(file, "utf8").split(/\r?\n/).filter((l) => l && !l.startsWith("#"))
    .map((l) => l.split(",").map((s) => s.trim()));
}

// An 8-bit grey, non-interlaced PNG's pixels: IDAT inflated and unfiltered.
function decodeGreyPng(file) {
  const b = fs.readFileSync(file);
  let width = 0, height = 0;
  const idat = [];
  for (let o = 8; o < b.length;) {
    const len = b.readUInt32BE(o), type = b.toString("ascii", o + 4, o + 8);
    const data = b.subarray(o + 8, o + 8 + len);
    if (type === "IHDR") {
      width = data.readUInt32BE(0); height = data.readUInt32BE(4);
      if (data[8] !== 8 || data[9] !== 0 || data[12] !== 0) throw new Error(`${file}: not 8-bit grey non-interlaced`);
    } else if (type === "IDAT") idat.push(data);
    o += 12 + len;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const out = Buffer.alloc(width * height);
  for (let r = 0; r < height; r++) {
    const filter = raw[r * (width + 1)], line = raw.subarray(r * (width + 1) + 1, (r + 1) * (width + 1));
    for (let c = 0; c < width; c++) {
      const a = c > 0 ? out[r * width + c - 1] : 0, up = r > 0 ? out[(r - 1) * width + c] : 0;
      const ul = r > 0 && c > 0 ? out[(r - 1) * width + c - 1] : 0;
      let pred = 0;
      if (filter === 1) pred = a;
      else if (filter === 2) pred = up;
      else if (filter === 3) pred = (a + up) >> 1;
      else if (filter === 4) {
        const p = a + up - ul, pa = Math.abs(p - a), pb = Math.abs(p - up), pc = Math.abs(p - ul);
        pred = pa <= pb && pa <= pc ? a : pb <= pc ? up : ul;
      }
      out[r * width + c] = (line[c] + pred) & 0xff;
    }
  }
  return { width, height, pixels: out };
}

function stamp(ns) {
  return { sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) };
}

function imageMessage(file, ns, encoding, frameId) {
  const header = { stamp: stamp(ns), frame_id: frameId };
  if (encoding === "png") return { header, format: "png", data: new Uint8Array(fs.readFileSync(file)) };
  if (encoding === "jpeg") {  // the image's .jpg twin, as written beside the .png
    return { header, format: "jpeg", data: new Uint8Array(fs.readFileSync(file.replace(/\.png$/, ".jpg"))) };
  }
  const { width, height, pixels } = decodeGreyPng(file);
  const channels = { mono8: 1, rgb8: 3, bgr8: 3, bgra8: 4 }[encoding];
  if (!channels) throw new Error(`unknown --image=${encoding}`);
  // rows padded by 3 bytes: step > width * channels, as some drivers write them
  const step = width * channels + 3;
  const data = new Uint8Array(step * height);
  for (let r = 0; r < height; r++) {
    for (let c = 0; c < width; c++) {
      for (let k = 0; k < channels; k++) data[r * step + c * channels + k] = k === 3 ? 255 : pixels[r * width + c];
    }
  }
  return { header, height, width, encoding, is_bigendian: 0, step, data };
}

// A ground-truth row [t ns, x, y, z, qw, qx, qy, qz] (the csv's column order).
function poseMessage(row, kind) {
  const header = { stamp: stamp(BigInt(row[0])), frame_id: "world" };
  const [x, y, z, qw, qx, qy, qz] = row.slice(1, 8).map(Number);
  const position = { x, y, z }, orientation = { x: qx, y: qy, z: qz, w: qw };
  if (kind === "pose") return { header, pose: { position, orientation } };
  if (kind === "transform") {
    return { header, child_frame_id: "body", transform: { translation: position, rotation: orientation } };
  }
  const zeros = new Float64Array(36);
  return { header, child_frame_id: "body", pose: { pose: { position, orientation }, covariance: zeros },
           twist: { twist: { linear: { x: 0, y: 0, z: 0 }, angular: { x: 0, y: 0, z: 0 } }, covariance: zeros } };
}

function imuMessage(row) {
  const [wx, wy, wz, ax, ay, az] = row.slice(1, 7).map(Number);
  const nine = new Float64Array(9);
  return { header: { stamp: stamp(BigInt(row[0])), frame_id: "imu0" }, orientation: { x: 0, y: 0, z: 0, w: 1 },
           orientation_covariance: nine, angular_velocity: { x: wx, y: wy, z: wz }, angular_velocity_covariance: nine,
           linear_acceleration: { x: ax, y: ay, z: az }, linear_acceleration_covariance: nine };
}

// Seconds with a decimal fraction as integer nanoseconds (exact, no floating point).
function secondsToNs(text) {
  const [whole, fraction = ""] = text.split(".");
  return (BigInt(whole) * 1000000000n + BigInt((fraction + "000000000").slice(0, 9))).toString();
}

// The ground truth as csv-ordered rows: data.csv (17 columns), else TUM text
// (t [s] x y z qx qy qz qw), else none.
function groundTruthRows(folder) {
  if (fs.existsSync(path.join(folder, "data.csv"))) return csv(path.join(folder, "data.csv"));
  const tum = path.join(folder, "groundtruth_tum.txt");
  if (!fs.existsSync(tum)) return [];
  return fs.readFileSync(tum, "utf8").split(/\r?\n/).filter((l) => l.trim() && !l.startsWith("#")).map((l) => {
    const [t, x, y, z, qx, qy, qz, qw] = l.trim().split(/\s+/);
    return [secondsToNs(t), x, y, z, qw, qx, qy, qz];
  });
}

// Every message of the folder: {topic, type, t (BigInt ns), make()} in stamp order.
function messages(a) {
  const mav0 = path.join(a.asl, "mav0"), list = [];
  const compressed = a.image === "png" || a.image === "jpeg";
  const imageType = compressed ? "sensor_msgs/msg/CompressedImage" : "sensor_msgs/msg/Image";
  for (const cam of [0, 1]) {
    let rows = csv(path.join(mav0, `cam${cam}`, "data.csv"));
    if (Number(a.frames) > 0) rows = rows.slice(0, Number(a.frames));
    for (const [t, file] of rows) {
      const png = path.join(mav0, `cam${cam}`, "data", file);
      list.push({ topic: `/cam${cam}/image_raw`, type: imageType, t: BigInt(t),
                  make: () => imageMessage(png, BigInt(t), a.image, `cam${cam}`) });
    }
  }
  for (const row of csv(path.join(mav0, "imu0", "data.csv"))) {
    list.push({ topic: "/imu0", type: "sensor_msgs/msg/Imu", t: BigInt(row[0]), make: () => imuMessage(row) });
  }
  const gtRows = groundTruthRows(path.join(mav0, "state_groundtruth_estimate0"));
  const gtType = { pose: "geometry_msgs/msg/PoseStamped", transform: "geometry_msgs/msg/TransformStamped",
                   odometry: "nav_msgs/msg/Odometry" }[a.groundtruth];
  for (const row of gtRows) {
    list.push({ topic: "/groundtruth", type: gtType, t: BigInt(row[0]), make: () => poseMessage(row, a.groundtruth) });
  }
  return list.sort((x, y) => (x.t < y.t ? -1 : x.t > y.t ? 1 : 0));
}

function serializer(type) {
  return new MessageWriter(parse(definitions[type], { ros2: true }));
}

async function compressor(kind) {
  if (kind === "none" || kind === "unchunked") return undefined;
  if (kind === "zstd") {
    const zstd = require("@foxglove/wasm-zstd");
    await zstd.isLoaded;
    return (data) => ({ compression: "zstd", compressedData: zstd.compress(data) });
  }
  if (kind === "lz4") {
    const lz4 = require("lz4js");  // LZ4 frames, as MCAP's lz4 chunks are
    return (data) => ({ compression: "lz4", compressedData: lz4.compress(data) });
  }
  throw new Error(`unknown --compression=${kind}`);
}

// A file sink for McapWriter.
class FileSink {
  constructor(file) { this.fd = fs.openSync(file, "w"); this.pos = 0n; }
  position() { return this.pos; }
  async write(buffer) { fs.writeSync(this.fd, buffer); this.pos += BigInt(buffer.byteLength); }
  close() { fs.closeSync(this.fd); }
}

async function writeMcap(a, list) {
  const sink = new FileSink(a.out);
  const writer = new McapWriter({ writable: sink, compressChunk: await compressor(a.compression), chunkSize: 1 << 20,
                                  useChunks: a.compression !== "unchunked" });
  await writer.start({ profile: "ros2", library: "vio-ros2-testdata" });
  const channels = new Map(), writers = new Map();
  for (const m of list) {
    if (channels.has(m.topic)) continue;
    const schemaId = await writer.registerSchema({ name: m.type, encoding: "ros2msg",
                                                   data: new TextEncoder().encode(definitions[m.type]) });
    channels.set(m.topic, await writer.registerChannel({ topic: m.topic, schemaId, messageEncoding: "cdr", metadata: new Map() }));
    if (!writers.has(m.type)) writers.set(m.type, serializer(m.type));
  }
  let sequence = 0;
  for (const m of list) {
    await writer.addMessage({ channelId: channels.get(m.topic), sequence: sequence++, logTime: m.t, publishTime: m.t,
                              data: writers.get(m.type).writeMessage(m.make()) });
  }
  await writer.end();
  sink.close();
}

function writeJsonl(a, list) {
  const fd = fs.openSync(a.out, "w"), writers = new Map();
  for (const m of list) {
    if (!writers.has(m.type)) writers.set(m.type, serializer(m.type));
    const cdr = Buffer.from(writers.get(m.type).writeMessage(m.make())).toString("base64");
    fs.writeSync(fd, JSON.stringify({ topic: m.topic, type: m.type, t: m.t.toString(), cdr }) + "\n");
  }
  fs.closeSync(fd);
}

async function main() {
  const a = args();
  const list = messages(a);
  if (a.format === "jsonl") writeJsonl(a, list);
  else await writeMcap(a, list);
}

main().catch((e) => { console.error(`write_bag.js: ${e.stack || e}`); process.exit(1); });
