// A flood of bad connection attempts against a running `plantscale gateway`
// while a real viewer (npm's @foxglove/ws-protocol FoxgloveClient) stays
// subscribed: issue 58's goal "1,000 connection attempts a second: each
// refused with a clear reason, nothing crashes, the run goes on". Run by
// tests/gateway/abuse.sh (which starts the gateway and a vehicle); from
// the directory where the npm packages are installed.
//
//   node abuse.mjs HOST PORT TOKEN CA GATEWAY_PID RATE SECONDS [SOURCE_ADDRESS]
//
// Phases: `before` (5 s, the viewer alone), `attack` (SECONDS at RATE
// attempts a second, each a new TCP connection from SOURCE_ADDRESS, default
// 127.0.0.2), `drain` (until the gateway has no connection left from the
// attack, at most 15 s), `after` (5 s). In the middle of the attack a second
// viewer (from 127.0.0.1) connects: does it get in, and how fast.
// The attempts, in turn:
//   badtoken   TLS, then a WebSocket upgrade with a wrong token (expects 401)
//   notls      a plain-text upgrade on the TLS port
//   garbage    2 KiB of random bytes
//   oversize   TLS, then an upgrade with a 16 KiB header
//   malformed  TLS, then bytes that are not HTTP
//   halfopen   TCP connected, then nothing (held until the attack ends)
//   slowtls    the first 5 bytes of a TLS record, then nothing (held)
// Measures per phase: the viewer's PLANTSCALE_GRID messages a second, their
// latency (arrival against the vehicle's stamp, p50 and p95: reported, not
// judged, as a simulated vehicle that falls behind real time on a loaded
// machine stamps its messages late) and
// longest gap, the gateway's CPU (from /proc/PID/stat), resident memory and
// open file descriptors (peak during the attack), the refusal events on
// PLANTSCALE_GATEWAY_EVENTS; per kind: attempts, how each ended. Prints one
// JSON object; exits 0 when the viewer kept receiving (each phase's grid
// rate within 20 % of `before`'s, no gap over 2 s), the gateway lived, no
// descriptor leaked (after <= before + 2), the refusal events stayed rate
// limited (<= 5 + 1 per 10 s started + 1), the attack reached 90 % of RATE,
// and the second viewer got in; 1 otherwise, saying why.
import foxglove from "@foxglove/ws-protocol";
import crypto from "node:crypto";
import fs from "node:fs";
import net from "node:net";
import tls from "node:tls";
import { isMainThread, parentPort, Worker, workerData } from "node:worker_threads";
import WebSocket from "ws";

const { FoxgloveClient } = foxglove;
const [host, portText, token, caFile, pidText, rateText, secondsText, sourceArg] = process.argv.slice(2);
const port = Number(portText);
const pid = Number(pidText);
const rate = Number(rateText);
const attackS = Number(secondsText);
const source = sourceArg || "127.0.0.2";
const ca = fs.readFileSync(caFile);
const url = `wss://${host}:${port}/`;
const clkTck = 100; // USER_HZ on Linux
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// --- the gateway process ---------------------------------------------------
const alive = () => fs.existsSync(`/proc/${pid}`);
const cpuTicks = () => {
  const stat = fs.readFileSync(`/proc/${pid}/stat`, "utf8");
  const f = stat.slice(stat.lastIndexOf(")") + 2).split(" ");
  return Number(f[11]) + Number(f[12]); // utime + stime (fields 14, 15)
};
const rssKb = () => Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${pid}/status`, "utf8"))[1]);
const fds = () => fs.readdirSync(`/proc/${pid}/fd`).length;
// The gateway's TCP connections on PORT, from /proc/PID/net/tcp (its
// namespace).
const gatewayConnections = () => {
  let n = 0;
  const hexPort = port.toString(16).toUpperCase().padStart(4, "0");
  for (const file of ["tcp", "tcp6"]) {
    let text = "";
    try {
      text = fs.readFileSync(`/proc/${pid}/net/${file}`, "utf8");
    } catch {
      continue;
    }
    for (const line of text.split("\n").slice(1)) {
      const f = line.trim().split(/\s+/);
      if (f.length < 4) continue;
      // The gateway's side (local port PORT) of a connection it still holds:
      // established, in the accept queue, or closed by the peer but not by it.
      if (f[1].endsWith(`:${hexPort}`) && ["01", "03", "08"].includes(f[3])) n++;
    }
  }
  return n;
};

// --- the viewer -------------------------------------------------------------
// Each viewer runs in a worker thread of its own, so that the load
// generator's busy event loop does not delay what the viewer receives: it
// stamps each message on arrival (ms, the same clock in every thread) and
// posts the stamps here.
const now = () => performance.timeOrigin + performance.now();
function viewer(name, localAddress) {
  const v = { name, grid: [], latency: [], events: [], connectedAt: null, closed: null, error: null };
  const w = new Worker(new URL(import.meta.url), {
    argv: process.argv.slice(2),
    workerData: { url: `${url}?token=${encodeURIComponent(token)}`, caFile, localAddress },
  });
  w.on("message", (m) => {
    if (m.grid) {
      v.grid.push(m.grid);
      v.latency.push(m.latency);
    }
    else if (m.event) v.events.push(m.event);
    else if (m.open) v.connectedAt = m.open;
    else if (m.close) v.closed = m.close;
    else if (m.error) v.error = m.error;
  });
  v.close = () => w.postMessage("close");
  v.worker = w;
  return v;
}
if (!isMainThread) {
  const { url: target, caFile: caPath, localAddress } = workerData;
  const ws = new WebSocket(target, [FoxgloveClient.SUPPORTED_SUBPROTOCOL], { ca: fs.readFileSync(caPath), localAddress });
  const client = new FoxgloveClient({ ws });
  const subs = new Map();
  client.on("open", () => parentPort.postMessage({ open: now() }));
  client.on("error", (e) => parentPort.postMessage({ error: String(e?.message ?? e) }));
  client.on("close", () => parentPort.postMessage({ close: now() }));
  client.on("advertise", (channels) => {
    for (const c of channels) {
      if (c.topic === "PLANTSCALE_GRID" || c.topic === "PLANTSCALE_GATEWAY_EVENTS") {
        subs.set(client.subscribe(c.id), c.topic);
      }
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const topic = subs.get(subscriptionId);
    // Latency: arrival against the vehicle's stamp (its wall clock, the
    // same host's).
    if (topic === "PLANTSCALE_GRID") parentPort.postMessage({ grid: now(), latency: now() - Number(timestamp) / 1e6 });
    if (topic === "PLANTSCALE_GATEWAY_EVENTS") {
      const log = JSON.parse(new TextDecoder().decode(data));
      parentPort.postMessage({ event: { at: now(), message: log.message } });
    }
  });
  parentPort.on("message", () => {
    client.close();
    setTimeout(() => process.exit(0), 100);
  });
}

if (isMainThread) await main();

async function main() {
// --- the attempts -----------------------------------------------------------
const kinds = ["badtoken", "notls", "garbage", "oversize", "malformed", "badtoken", "notls", "garbage", "halfopen", "slowtls"];
const stats = Object.fromEntries([...new Set(kinds)].map((k) => [k, { attempts: 0, outcomes: {} }]));
// One TLS context for every attempt (a context per connection costs the
// load generator more than the gateway); the attacker checks nothing.
const attackContext = tls.createSecureContext({});
const held = new Set(); // half-open sockets, closed when the attack ends
let inFlight = 0;
const upgrade = (tok, extra = "") =>
  `GET /?token=${tok} HTTP/1.1\r\nHost: ${host}:${port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n` +
  `Sec-WebSocket-Key: ${crypto.randomBytes(16).toString("base64")}\r\nSec-WebSocket-Version: 13\r\n` +
  `Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n${extra}\r\n`;

function attempt(kind) {
  const s = stats[kind];
  s.attempts++;
  inFlight++;
  let reply = "";
  let done = false;
  const end = (outcome) => {
    if (done) return;
    done = true;
    inFlight--;
    s.outcomes[outcome] = (s.outcomes[outcome] || 0) + 1;
  };
  const useTls = kind === "badtoken" || kind === "oversize" || kind === "malformed";
  const sock = useTls
    ? tls.connect({ host, port, secureContext: attackContext, rejectUnauthorized: false, localAddress: source })
    : net.connect({ host, port, localAddress: source });
  sock.setTimeout(15_000, () => {
    end("no answer in 15 s");
    sock.destroy();
  });
  sock.on("error", (e) => end(`error ${e.code ?? e.message}`));
  sock.on("data", (d) => {
    reply += d.toString("latin1");
  });
  sock.on("close", () => {
    held.delete(sock);
    const status = /^HTTP\/1\.1 (\d+)/.exec(reply);
    end(status ? `HTTP ${status[1]}` : reply.length ? "closed after non-HTTP bytes" : "closed, nothing sent back");
  });
  sock.on(useTls ? "secureConnect" : "connect", () => {
    if (kind === "badtoken") sock.write(upgrade(crypto.randomBytes(32).toString("hex")));
    else if (kind === "oversize") sock.write(upgrade("x", `X-Pad: ${"a".repeat(16 * 1024)}\r\n`));
    else if (kind === "malformed") sock.write("\x00\x01 NOT HTTP \xff\r\n\r\n");
    else if (kind === "notls") sock.write(upgrade("x"));
    else if (kind === "garbage") sock.write(crypto.randomBytes(2048));
    else if (kind === "slowtls") {
      sock.write(Buffer.from([0x16, 0x03, 0x01, 0x02, 0x00]));
      held.add(sock);
    } else if (kind === "halfopen") held.add(sock);
  });
}

// --- phases -----------------------------------------------------------------
const sample = () => ({ t: now(), ticks: cpuTicks(), rssKb: rssKb(), fds: fds(), conns: gatewayConnections() });
const phase = (name, a, b, v) => {
  const idx = v.grid.map((t, i) => i).filter((i) => v.grid[i] >= a.t && v.grid[i] < b.t);
  const grid = idx.map((i) => v.grid[i]);
  const lat = idx.map((i) => v.latency[i]).sort((x, y) => x - y);
  const pct = (q) => (lat.length ? +(lat[Math.min(lat.length - 1, Math.floor(q * lat.length))] / 1000).toFixed(3) : null);
  let gap = 0;
  for (let i = 1; i < grid.length; i++) gap = Math.max(gap, grid[i] - grid[i - 1]);
  const s = (b.t - a.t) / 1000;
  return {
    phase: name,
    seconds: +s.toFixed(2),
    gridPerS: +(grid.length / s).toFixed(2),
    longestGridGapS: +(gap / 1000).toFixed(3),
    gridLatencyP50S: pct(0.5),
    gridLatencyP95S: pct(0.95),
    gatewayCpuPercent: +((100 * (b.ticks - a.ticks)) / clkTck / s).toFixed(1),
    rssKbStart: a.rssKb,
    rssKbEnd: b.rssKb,
    fdsStart: a.fds,
    fdsEnd: b.fds,
    refusalEvents: v.events.filter((e) => e.at >= a.t && e.at < b.t && /refused/.test(e.message)).length,
  };
};

const result = { rate, attackS, source };
const problems = [];
const v1 = viewer("viewer", "127.0.0.1");
for (let i = 0; i < 300 && v1.grid.length < 5; i++) await sleep(100);
if (v1.grid.length < 5) {
  console.log(JSON.stringify({ ...result, why: `the viewer got ${v1.grid.length} grid messages in 30 s: is the vehicle running?` }));
  process.exit(1);
}
const s0 = sample();
await sleep(5000);
const s1 = sample();

// The attack: RATE a second, in batches every 10 ms.
let peakRss = s1.rssKb, peakFds = s1.fds, peakConns = s1.conns;
const started = performance.now();
let launched = 0, k = 0;
let v2 = null, v2Start = 0, lastSample = 0;
while (performance.now() - started < attackS * 1000) {
  const due = Math.floor(((performance.now() - started) / 1000) * rate);
  for (; launched < due; launched++) attempt(kinds[k++ % kinds.length]);
  if (!v2 && performance.now() - started >= (attackS * 1000) / 2) {
    v2Start = now();
    v2 = viewer("second viewer", "127.0.0.1");
  }
  if (performance.now() - lastSample >= 250) {
    lastSample = performance.now();
    peakRss = Math.max(peakRss, rssKb());
    peakFds = Math.max(peakFds, fds());
    peakConns = Math.max(peakConns, gatewayConnections());
  }
  await sleep(10);
}
const attackWall = (performance.now() - started) / 1000;
const s2 = sample();
peakRss = Math.max(peakRss, s2.rssKb);
peakFds = Math.max(peakFds, s2.fds);
for (const sock of held) sock.destroy();
// Drain: every attempt ended, and the gateway holds no attack connection
// (only the two viewers').
const drainStart = performance.now();
while (performance.now() - drainStart < 15_000 && (inFlight > 0 || gatewayConnections() > 2)) await sleep(100);
const s3 = sample();
await sleep(5000);
const s4 = sample();
v1.close();
v2?.close();

result.attempts = launched;
result.attemptsPerS = +(launched / attackWall).toFixed(0);
result.stillInFlight = inFlight;
result.kinds = stats;
result.phases = [phase("before", s0, s1, v1), phase("attack", s1, s2, v1), phase("drain", s2, s3, v1), phase("after", s3, s4, v1)];
result.attackPeak = { rssKb: peakRss, fds: peakFds, gatewayConnections: peakConns };
result.drainS = +((s3.t - s2.t) / 1000).toFixed(2);
result.gatewayConnectionsAfter = s4.conns;
result.secondViewer = v2?.connectedAt
  ? { connected: true, afterS: +((v2.connectedAt - v2Start) / 1000).toFixed(3), gridMessages: v2.grid.length }
  : { connected: false, error: v2?.error };
result.refusalEventTexts = v1.events.filter((e) => e.at >= s1.t).map((e) => e.message).slice(0, 20);
result.gatewayAlive = alive();

const [before, attack, drain, after] = result.phases;
if (!result.gatewayAlive) problems.push("the gateway died");
if (result.attemptsPerS < 0.9 * rate) problems.push(`${result.attemptsPerS} attempts/s, below 90 % of ${rate}`);
for (const p of [attack, drain, after]) {
  if (p.seconds >= 2 && Math.abs(p.gridPerS - before.gridPerS) > 0.2 * before.gridPerS) {
    problems.push(`${p.phase}: the viewer got ${p.gridPerS} grid/s against ${before.gridPerS} before (over 20 % off)`);
  }
  if (p.longestGridGapS > 2) problems.push(`${p.phase}: the viewer went ${p.longestGridGapS} s without a grid message`);
}
if (after.fdsEnd > before.fdsStart + 2) problems.push(`descriptors leaked: ${before.fdsStart} before, ${after.fdsEnd} after`);
const events = attack.refusalEvents + drain.refusalEvents + after.refusalEvents;
const allowed = 5 + Math.ceil((attackS + result.drainS + 5) / 10) + 1;
if (events > allowed) problems.push(`${events} refusal events, more than ${allowed} (not rate limited)`);
if (!result.secondViewer.connected) problems.push(`a viewer connecting during the attack did not get in (${v2?.error ?? "no answer"})`);
if (v1.closed) problems.push("the viewer's connection closed");
result.problems = problems;
console.log(JSON.stringify(result, null, 1));
await sleep(300);
  process.exit(problems.length ? 1 : 0);
}
