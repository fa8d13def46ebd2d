#!/usr/bin/env node
// bench/web's counting proxy: both clients (CesiumJS in Chromium, relief
// view) fetch from `relief serve` through it, so their requests and bytes
// are counted at the same place, the same way: the body bytes the server
// sent (gzip-compressed where it compressed them), per path class.
//
//   node bench/web-proxy.cjs LISTEN_PORT UPSTREAM_PORT
//
// Listens on 127.0.0.1:LISTEN_PORT (0: any free port; the port is printed
// as the first line of stdout) and forwards every request to
// 127.0.0.1:UPSTREAM_PORT with keep-alive. Control paths, answered by the
// proxy itself and not counted:
//   GET /.bench/counts   {"terrain": {requests, bytes}, "page": ..., "store": ..., statuses}
//   GET /.bench/reset    zeroes the counts
// Classes: "terrain" /terrain/ (Cesium's tiles and layer.json), "page"
// /view/, /lib/ and /imagery/ (the page, its libraries, and its probe for
// an imagery layer), "store" everything else
// (the store's own files: manifest, level indices, tiles).
"use strict";

const http = require("http");

const [listenPort, upstreamPort] = process.argv.slice(2).map(Number);
if (!Number.isInteger(listenPort) || !Number.isInteger(upstreamPort)) {
  process.stderr.write("usage: web-proxy.cjs LISTEN_PORT UPSTREAM_PORT\n");
  process.exit(2);
}

const agent = new http.Agent({ keepAlive: true, maxSockets: 64 });
let counts;
function reset() {
  counts = { statuses: {} };
  for (const c of ["terrain", "page", "store"]) counts[c] = { requests: 0, bytes: 0 };
}
reset();

function classOf(url) {
  const p = url.split("?")[0];
  if (p.startsWith("/terrain/")) return "terrain";
  if (p.startsWith("/view") || p.startsWith("/lib/") || p.startsWith("/imagery/")) return "page";
  return "store";
}

const server = http.createServer((req, res) => {
  if (req.url === "/.bench/counts" || req.url === "/.bench/reset") {
    if (req.url === "/.bench/reset") reset();
    const body = JSON.stringify(counts);
    res.writeHead(200, { "Content-Type": "application/json", "Content-Length": body.length });
    res.end(body);
    return;
  }
  const kind = classOf(req.url);
  const upstream = http.request(
    {
      host: "127.0.0.1",
      port: upstreamPort,
      method: req.method,
      path: req.url,
      headers: req.headers,
      agent,
    },
    (answer) => {
      res.writeHead(answer.statusCode, answer.rawHeaders);
      let bytes = 0;
      answer.on("data", (chunk) => {
        bytes += chunk.length;
      });
      answer.on("end", () => {
        counts[kind].requests += 1;
        counts[kind].bytes += bytes;
        counts.statuses[answer.statusCode] = (counts.statuses[answer.statusCode] || 0) + 1;
      });
      answer.pipe(res);
    },
  );
  upstream.on("error", (e) => {
    if (!res.headersSent) res.writeHead(502);
    res.end();
    process.stderr.write(`web-proxy: ${req.url}: ${e.message}\n`);
  });
  req.pipe(upstream);
});
server.keepAliveTimeout = 60000;
server.listen(listenPort, "127.0.0.1", () => {
  process.stdout.write(`${server.address().port}\n`);
});
