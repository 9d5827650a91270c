// bench_study.mjs — bounded load run of the study server on loopback: N simulated participants answer all
// their trials concurrently (GET next trial, POST answer), then the answers are counted through the export.
// Prints answers/s, p50/p99 POST latency and whether every acknowledged answer is stored exactly once.
//   node bench_study.mjs BASE_URL ADMIN_TOKEN CODE...
// By default every participant connects from 127.0.0.1, as a lab behind one NAT or reverse proxy does (issue 32.3);
// BENCH_ADDRESSES=many gives each its own loopback address (127.0.1.2, .3, ...), as participants at home have.
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
// BENCH_THINK_MS: mean pause of a participant before each answer (watching the clips; uniform in 0..2x the mean,
// from a seeded generator); 0 (default): answer at once, the server's saturation.
const thinkMs = Number(process.env.BENCH_THINK_MS || 0);
let seed = 12345;
const rand = () => ((seed = (Math.imul(seed, 1103515245) + 12345) >>> 0) / 4294967296);
const sleep = ms => new Promise(r => setTimeout(r, ms));
const lat = [];
let acked = 0;
const t0 = performance.now();
await Promise.all(codes.map(async (code, p) => {
  const many = process.env.BENCH_ADDRESSES === 'many';
  const agent = new http.Agent({ keepAlive: true, ...(many ? { localAddress: `127.0.${1 + Math.floor((p + 2) / 256)}.${(p + 2) % 256}` } : {}) });
  for (let i = 0; i < 1000; i++) {                       // bounded: at most 1000 trials per participant
    const t = JSON.parse((await request(agent, `/api/${code}/trial`)).text);
    if (t.done) break;
    if (thinkMs > 0) await sleep(2 * thinkMs * rand());
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
const lines = csv.trim().split('\n');
const typeCol = lines[0].split(',').indexOf('trial_type'); // the export has every answered trial (issue 27.9)
const rows = lines.slice(1).filter(r => typeCol < 0 || r.split(',')[typeCol] === 'test');
const distinct = new Set(rows.map(r => r.split(',').slice(0, 2).join(','))).size;
console.log(`${codes.length} participants, ${acked} answers acknowledged in ${secs.toFixed(2)} s: ${(acked / secs).toFixed(0)} answers/s`);
console.log(`POST /answer latency: p50 ${q(0.5).toFixed(2)} ms, p99 ${q(0.99).toFixed(2)} ms (durable commit before the reply)`);
console.log(`export: ${rows.length} test ratings, ${distinct} distinct (test trials; the export's catch and training rows left out)`);
process.exit(0);
