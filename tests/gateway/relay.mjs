// A TCP relay for tests/station_connect_cli_test.sh: listens on 127.0.0.1:LISTEN
// and joins each connection to 127.0.0.1:TARGET, byte for byte (TLS passes
// through untouched). Stopping the relay's process (SIGSTOP) cuts the link
// the way a lost radio link does: nothing arrives, nothing is closed;
// SIGCONT brings it back. Node's own modules only.
// usage: node relay.mjs LISTEN_PORT TARGET_PORT
import net from "node:net";

const [listen, target] = process.argv.slice(2).map(Number);
const server = net.createServer((client) => {
  const upstream = net.connect(target, "127.0.0.1");
  const end = () => {
    client.destroy();
    upstream.destroy();
  };
  client.on("error", end).on("close", end);
  upstream.on("error", end).on("close", end);
  client.pipe(upstream);
  upstream.pipe(client);
});
server.listen(listen, "127.0.0.1", () => console.log(`relay: 127.0.0.1:${listen} -> 127.0.0.1:${target}`));
process.on("SIGTERM", () => process.exit(0));
