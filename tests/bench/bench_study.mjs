// bench_study.mjs — bounded load run of the study server on loopback: N simulated participants answer all
// their trials concurrently (GET next trial, POST answer), then the answers are counted through the export.
// Prints answers/s, p50/p99 POST latency and whether every acknowledged answer is stored exactly once.
//   node bench_study.mjs BASE_URL ADMIN_TOKEN CODE...
// Each participant connects from its own loopback address (127.0.0.2, .3, ...), as real participants come from their
// own machines: the server caps connections per client address (issue 12.4), and 50 participants behind one address
// would be refused by that cap, not measure the server.
import http from 'node:http';
const [base, token, ...codes] = process.argv.slice(2);
function request(agent, path, method = 'GET', body = null, headers = {}) {
  return new Promise((resolve, reject) => {
    const req = http.request(`${base}${path}`, { method, agent, headers }, res => {
      let text = '';
      res.setEncoding('utf8');
      res.on('data', d => { text += d; });
      res.on('end', () => resolve({ status: res.statusCode, text }));
    });
    req.on('error', reject);
    if (body) req.write(body);
    req.end();
  });
}
const lat = [];
let acked = 0;
const t0 = performance.now();
await Promise.all(codes.map(async (code, p) => {
  const agent = new http.Agent({ keepAlive: true, localAddress: `127.0.${1 + Math.floor((p + 2) / 256)}.${(p + 2) % 256}` });
  for (let i = 0; i < 1000; i++) {                       // bounded: at most 1000 trials per participant
    const t = JSON.parse((await request(agent, `/api/${code}/trial`)).text);
    if (t.done) break;
    const s = performance.now();
    const body = JSON.stringify({ trial: t.index, answer: ((p + i) % 5) - 2, rt_ms: 1000 });
    const r = await request(agent, `/api/${code}/answer`, 'POST', body,
      { 'content-type': 'application/json', 'content-length': Buffer.byteLength(body) });
    lat.push(performance.now() - s);
    if (r.status === 200) acked++;
    else throw new Error(`HTTP ${r.status}`);
  }
  agent.destroy();
}));
const secs = (performance.now() - t0) / 1000;
lat.sort((a, b) => a - b);
const q = f => lat[Math.min(lat.length - 1, Math.floor(f * lat.length))];
const exp = await fetch(`${base}/admin/export.csv`, { headers: { authorization: `Bearer ${token}` } }); // never ?token=
if (exp.status !== 200) throw new Error(`export: HTTP ${exp.status}`);
const csv = await exp.text();
const rows = csv.trim().split('\n').slice(1);
const distinct = new Set(rows.map(r => r.split(',').slice(0, 2).join(','))).size;
console.log(`${codes.length} participants, ${acked} answers acknowledged in ${secs.toFixed(2)} s: ${(acked / secs).toFixed(0)} answers/s`);
console.log(`POST /answer latency: p50 ${q(0.5).toFixed(2)} ms, p99 ${q(0.99).toFixed(2)} ms (durable commit before the reply)`);
console.log(`export: ${rows.length} test ratings, ${distinct} distinct (test trials only; catch trials are not exported)`);
process.exit(0);
