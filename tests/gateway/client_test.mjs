// A real Foxglove WebSocket client (npm's @foxglove/ws-protocol over `ws`)
// against `plantscale gateway`, for tests/gateway_cli_test.sh.
//
//   node client_test.mjs refused URL TOKEN CA
//     expects the upgrade refused with HTTP 401 and no serverInfo.
//   node client_test.mjs untrusted URL TOKEN CA
//     with a CA that did not sign the gateway's certificate: expects the
//     TLS handshake to fail (the client refuses the server). With
//     EXPECT_CODE set (e.g. CERT_HAS_EXPIRED, ERR_TLS_CERT_ALTNAME_INVALID),
//     it must fail with that code: an expired or wrong-name certificate.
//   node client_test.mjs watch URL TOKEN CA READY_FILE TOPICS [command]
//     subscribes to every advertised channel, touches READY_FILE, checks
//     every message against its channel's JSON Schema (Ajv) and waits until
//     each topic of the comma-separated TOPICS has arrived. With "command"
//     it publishes, at the vehicle's first heartbeat, one (unsigned) set-mode command on
//     PLANTSCALE_COMMAND and waits for the vehicle's `command` event (an
//     operator) or for the gateway's refusal status (a viewer).
// Prints one JSON line (counts per topic, schema failures, statuses) and
// exits 0 when all held, 1 otherwise. Gives up after 90 s.
import foxglove from "@foxglove/ws-protocol";
import Ajv from "ajv";
import fs from "node:fs";
import WebSocket from "ws";

const { FoxgloveClient } = foxglove; // a CommonJS package
const [mode, url, token, caFile, readyFile, topicList, command] = process.argv.slice(2);
const ca = fs.readFileSync(caFile);
const target = `${url}?token=${encodeURIComponent(token)}`;
const result = { mode, counts: {}, invalid: [], statuses: [], serverInfo: null, errors: [] };
const finish = (ok, why) => {
  if (why) result.why = why;
  console.log(JSON.stringify(result));
  process.exit(ok ? 0 : 1);
};
setTimeout(() => finish(false, "timed out"), 90_000).unref();

const ws = new WebSocket(target, [FoxgloveClient.SUPPORTED_SUBPROTOCOL], { ca });

if (mode === "untrusted") {
  ws.on("open", () => finish(false, "connected through a certificate it does not trust"));
  ws.on("unexpected-response", () => finish(false, "reached HTTP through a certificate it does not trust"));
  ws.on("error", (e) => {
    result.errors.push(String(e.code ?? e.message));
    const expected = process.env.EXPECT_CODE;
    const ok = expected ? String(e.code) === expected : /CERT|SIGNATURE|SELF_SIGNED|UNABLE_TO/.test(String(e.code));
    finish(ok, ok ? undefined : `failed with ${e.code}, expected ${expected ?? "a certificate error"}`);
  });
} else if (mode === "refused") {
  ws.on("unexpected-response", (_req, res) => {
    result.httpStatus = res.statusCode;
    let body = "";
    res.on("data", (d) => (body += d));
    res.on("end", () => {
      result.body = body.trim();
      finish(res.statusCode === 401, res.statusCode === 401 ? undefined : "not 401");
    });
  });
  ws.on("open", () => finish(false, "the upgrade was accepted"));
  ws.on("error", (e) => result.errors.push(String(e.message)));
} else {
  const client = new FoxgloveClient({ ws });
  const ajv = new Ajv({ strict: false, allErrors: true });
  const channels = new Map(); // subscription id -> { topic, validate }
  const wanted = new Set((topicList || "").split(",").filter(Boolean));
  let commandChannel = null;
  let commandSent = false;
  let commandDone = !command;

  // WATCH_FOR_S (tests/gateway/load.sh): stay connected that long, then
  // report (ok when every topic arrived and all were valid).
  const watchFor = Number(process.env.WATCH_FOR_S || 0);
  if (watchFor > 0) {
    setTimeout(() => {
      const missing = [...wanted].filter((t) => !result.counts[t]);
      finish(missing.length === 0 && result.invalid.length === 0, missing.length ? `missing ${missing}` : undefined);
    }, watchFor * 1000);
  }
  const maybeDone = () => {
    if (watchFor > 0) return;
    const missing = [...wanted].filter((t) => !result.counts[t]);
    if (missing.length === 0 && commandDone) finish(result.invalid.length === 0, result.invalid.length ? "schema failures" : undefined);
  };

  const sendCommand = () => {
    commandSent = true;
    const role = result.serverInfo?.metadata?.role;
    commandChannel = client.advertise({ topic: "PLANTSCALE_COMMAND", encoding: "json", schemaName: "plantscale.Command" });
    const now = (BigInt(Date.now()) * 1000n).toString();
    const payload = { utime: now, seq: now, command: 3, mode: 1, origin: `foxglove-test@${role}`, mac: "" };
    client.sendMessage(commandChannel, new TextEncoder().encode(JSON.stringify(payload)));
    result.commandSentAs = role;
  };

  client.on("serverInfo", (info) => (result.serverInfo = info));
  client.on("status", (s) => {
    result.statuses.push(s.message);
    if (command && result.serverInfo?.metadata?.role === "viewer" && /role viewer may not publish/.test(s.message)) {
      result.commandRefused = true;
      commandDone = true;
      maybeDone();
    }
  });
  client.on("error", (e) => result.errors.push(String(e?.message ?? e)));
  client.on("close", () => finish(false, "closed by the server"));
  client.on("message", ({ data }) => (result.bytes = (result.bytes || 0) + data.byteLength));
  client.on("advertise", (advertised) => {
    for (const c of advertised) {
      const schema = JSON.parse(c.schema);
      const id = client.subscribe(c.id);
      channels.set(id, { topic: c.topic, validate: ajv.compile(schema), schemaName: c.schemaName });
    }
    fs.writeFileSync(readyFile, "ready\n");
  });
  client.on("message", ({ subscriptionId, data }) => {
    const c = channels.get(subscriptionId);
    if (!c) return result.errors.push(`message on unknown subscription ${subscriptionId}`);
    const text = new TextDecoder().decode(data);
    let msg;
    try {
      msg = JSON.parse(text);
    } catch {
      return result.invalid.push({ topic: c.topic, error: "not JSON" });
    }
    if (!c.validate(msg)) {
      if (result.invalid.length < 5) result.invalid.push({ topic: c.topic, errors: c.validate.errors });
      else result.invalid.push({ topic: c.topic });
    }
    result.counts[c.topic] = (result.counts[c.topic] || 0) + 1;
    result.topicBytes = result.topicBytes || {};
    result.topicBytes[c.topic] = (result.topicBytes[c.topic] || 0) + data.byteLength;
    // The vehicle is running once its heartbeat arrives: the command goes now.
    if (c.topic === "PLANTSCALE_HEALTH" && command && !commandSent) sendCommand();
    if (c.topic === "PLANTSCALE_EVENTS" && msg.name === "command" && /foxglove-test@operator/.test(msg.message)) {
      result.commandEvent = msg.message;
      commandDone = true;
    }
    maybeDone();
  });
}
