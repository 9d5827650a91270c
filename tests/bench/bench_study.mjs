// bench_study.mjs — bounded load run of the study server on loopback: N simulated participants answer all
// their trials concurrently (GET next trial, POST answer), then the answers are counted through the export.
// Prints answers/s, p50/p99 POST latency and whether every acknowledged answer is stored exactly once.
//   node bench_study.mjs BASE_URL ADMIN_TOKEN CODE...
const [base, token, ...codes] = process.argv.slice(2);
const lat = [];
let acked = 0;
const t0 = performance.now();
await Promise.all(codes.map(async (code, p) => {
  for (let i = 0; i < 1000; i++) {                       // bounded: at most 1000 trials per participant
    const t = await (await fetch(`${base}/api/${code}/trial`)).json();
    if (t.done) break;
    const s = performance.now();
    const r = await fetch(`${base}/api/${code}/answer`, { method: 'POST',
      body: JSON.stringify({ trial: t.index, answer: ((p + i) % 5) - 2, rt_ms: 1000 }) });
    await r.text();
    lat.push(performance.now() - s);
    if (r.status === 200) acked++;
    else throw new Error(`HTTP ${r.status}`);
  }
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
