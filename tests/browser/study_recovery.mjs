// study_recovery.mjs — the participant page and the server under failure (issue 27), in Debian's Chromium
// (playwright-core). It runs `taslab study serve` itself, on a fixed port, so that it can SIGKILL and restart it:
//   1. after a break the server is down when Continue is pressed: no answer panel (no key or click can answer) until
//      this trial's clips have played, a visible retry message, recovery when the server is back (items 27.1, 27.2);
//   2. the server is killed when the page asks for a clip: "Connection lost, retrying" shows, the page recovers by
//      itself once the server is back, and the message is gone on the next trial (27.2, 27.3);
//   3. one link in two browser contexts: the window taken over is told so and stores nothing; every answer the
//      server holds is one the page was told was saved (27.4);
//   4. both clips of every trial the same byte length, and no trial kind but training in the trial JSON (27.6);
//   5. a second `study serve` on the same study refused in one line (27.5); the log lines of answers, restarts and
//      completions, and the live status page with the admin token (27.8, screenshot WORK/status.png): its P.910-crowd
//      flags and broken playbacks per participant (issue 28) as the tally and the export say (one playback hidden for
//      certain); a gold trial in each plan, blinded like the others.
//   node study_recovery.mjs TASLAB_BINARY STUDY.db WORK_DIR
import { chromium } from 'playwright-core';
import { spawn, spawnSync } from 'node:child_process';
import { createServer } from 'node:net';
import { readFileSync } from 'node:fs';
const require_file = p => readFileSync(p, 'utf8');

const [taslab, db, work] = process.argv.slice(2);
const timer = setTimeout(() => { console.error('study_recovery: timed out'); process.exit(2); }, 240000);
const sleep = ms => new Promise(r => setTimeout(r, ms));
const port = await new Promise(r => { const s = createServer(); s.listen(0, '127.0.0.1', () => { const p = s.address().port; s.close(() => r(p)); }); });
const base = `http://127.0.0.1:${port}`;
let server = null, serverLog = '', status = 0;
const fail = msg => { console.error('FAIL ' + msg); status = 1; };

async function startServer() {
  server = spawn(taslab, ['study', 'serve', '--db', db, '--port', String(port)], { stdio: ['ignore', 'pipe', 'pipe'] });
  server.stdout.on('data', d => { serverLog += d; });
  server.stderr.on('data', d => { serverLog += d; });
  for (let i = 0; i < 200; i++) {   // listening, and its first lines read (the token comes from them)
    try { if ((await fetch(base + '/')).ok && /admin token/.test(serverLog)) return; } catch (e) { /* not yet */ }
    await sleep(50);
  }
  throw new Error('the server did not start:\n' + serverLog);
}
async function killServer() {
  const s = server;
  server = null;
  const gone = new Promise(r => s.once('exit', r));
  s.kill('SIGKILL');
  await gone;
}
const panel = (page, id) => page.evaluate(i => getComputedStyle(document.getElementById(i)).display === 'block', id);
const waitPanel = (page, ids, timeout = 30000) => page.waitForFunction(list => list.some(id =>
  getComputedStyle(document.getElementById(id)).display === 'block'), ids, { timeout });
const statusText = page => page.evaluate(() => {
  const s = document.getElementById('status');
  return getComputedStyle(s).display === 'none' ? '' : s.textContent;
});
// Answers the server holds for a participant, counted or not (the admin status; the token is set once it started).
let token = null;
async function stored(label) {
  const r = await fetch(`${base}/admin/status`, { headers: { authorization: 'Bearer ' + token } });
  return (await r.json()).participants.find(p => p.label === label).answered;
}
async function answered(code) { return (await (await fetch(`${base}/api/${code}/trial`)).json()).answered; }
// Answers the trial on the ask panel by key and waits for what comes next.
async function answerNow(page, key) {
  const before = await page.evaluate(() => document.body.dataset.trial);    // the trial's index (a retake
  await page.keyboard.press(key);                                            // keeps the progress text)
  await page.waitForFunction(b => document.body.dataset.trial !== b ||
    ['done', 'problem'].some(id => getComputedStyle(document.getElementById(id)).display === 'block'), before, { timeout: 30000 });
}

let browser;
const trials = [];   // every trial JSON the pages received
try {
  await startServer();
  token = (serverLog.match(/admin token ([0-9a-f]{32})/) || [])[1];
  if (!token) throw new Error('no admin token in: ' + serverLog);
  const links = spawnSync(taslab, ['study', 'links', '--db', db], { encoding: 'utf8' }).stdout.trim().split('\n');
  const codes = links.map(l => l.replace(/.*\/p\//, ''));

  // 5a. A second server on the same study: refused, one line, non-zero exit.
  const second = spawnSync(taslab, ['study', 'serve', '--db', db, '--port', '0'], { encoding: 'utf8', timeout: 20000 });
  const secondOut = (second.stdout + second.stderr).trim();
  if (second.status === 0 || secondOut.split('\n').length !== 1 || !/being served already/.test(secondOut))
    fail(`a second 'study serve' on the same study: exit ${second.status}, output:\n${secondOut}`);

  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--autoplay-policy=no-user-gesture-required'],
  });
  const watch = page => {
    page.on('response', async r => {
      if (new URL(r.url()).pathname.endsWith('/trial') && r.status() === 200) trials.push(await r.json().catch(() => ({})));
    });
    page.on('pageerror', e => fail('page error: ' + e.message));
  };

  // ---- participant 1: a break with the server down, then a clip download with the server killed
  const ctx1 = await browser.newContext();
  const page = await ctx1.newPage();
  watch(page);
  await page.goto(`${base}/p/${codes[0]}`);
  await page.click('#start');
  let acknowledged = 0, sawBreakDown = false, sawClipKill = false;
  let killOnClip = false;
  await page.route('**/clips/**', async route => {
    if (killOnClip) { killOnClip = false; await killServer(); }
    await route.continue().catch(() => route.abort().catch(() => {}));
  });
  for (let step = 0; step < 40; step++) {
    await waitPanel(page, ['ask', 'break', 'done']);
    if (await panel(page, 'done')) break;
    if (await panel(page, 'break')) {
      if (!sawBreakDown) {
        // 1. The server is down when Continue is pressed: the page must not offer the answer panel.
        sawBreakDown = true;
        const before = await stored('P001');   // every stored answer, broken playbacks' too (progress skips those)
        await killServer();
        await page.click('#resume');
        await sleep(2500);
        if (await panel(page, 'ask')) fail('after a break with the server down, the answer panel is shown before the clips played');
        for (const k of ['1', '2', '3', '4', '5']) await page.keyboard.press(k);
        const msg = await statusText(page);
        if (!/Connection lost/.test(msg)) fail(`no visible retry message while the server is down (status '${msg}')`);
        await startServer();
        await waitPanel(page, ['ask']);
        const after = await stored('P001');
        if (after !== before) fail(`keys pressed before the clips played stored an answer (${before} -> ${after} stored)`);
        if (await statusText(page)) fail('the retry message stays after the server came back');
      } else {
        await page.click('#resume');
      }
      continue;
    }
    const armed = sawBreakDown && !sawClipKill;
    killOnClip = armed;                          // 2./3. the server dies when the page asks for the next trial's clip
    await answerNow(page, String(1 + (acknowledged % 5)));
    acknowledged++;
    if (armed) {
      sawClipKill = true;
      await page.waitForFunction(() => /Connection lost/.test(document.getElementById('status').textContent), null, { timeout: 30000 });
      if (!(await panel(page, 'loading')) && !(await panel(page, 'break')))
        fail('while the clip cannot be fetched the page shows neither the loading panel nor the break');
      await sleep(1500);
      await startServer();
      await waitPanel(page, ['ask', 'break', 'done'], 60000);
      const msg = await statusText(page);
      if (msg) fail(`after the clips came, the retry message stays: '${msg}'`);
    }
  }
  if (!(await panel(page, 'done'))) fail('participant 1 did not reach the end');
  if (!sawBreakDown || !sawClipKill) fail(`scenarios not reached (break with server down ${sawBreakDown}, clip kill ${sawClipKill})`);
  const state1 = await (await fetch(`${base}/api/${codes[0]}/trial`)).json();
  // a playback the server judges broken (frames dropped on a loaded machine) is stored, not counted, and retaken, so
  // the page may acknowledge more answers than the plan counts; the status page below counts every stored answer
  if (!state1.done || state1.answered !== state1.total || acknowledged < state1.total)
    fail(`participant 1: server holds ${state1.answered}/${state1.total} answers, the page had ${acknowledged} acknowledged`);
  console.log(`participant 1: ${acknowledged} answers, the server killed twice (at a break, at a clip download); server ${state1.answered}/${state1.total}`);

  // ---- participant 2: the link open in two browser contexts
  const ctxA = await browser.newContext(), ctxB = await browser.newContext();
  const pa = await ctxA.newPage(), pb = await ctxB.newPage();
  watch(pa); watch(pb);
  await pa.goto(`${base}/p/${codes[1]}`);
  await pa.click('#start');
  await waitPanel(pa, ['ask']);
  await pb.goto(`${base}/p/${codes[1]}`);
  await pb.click('#start');                  // B takes the link over
  await waitPanel(pb, ['ask']);
  const n0 = await answered(codes[1]);
  await answerNow(pb, '4');                  // B answers the trial A is also showing
  const n1 = await answered(codes[1]);
  await answerNow(pa, '2');                  // A answers the same trial: it must be told, and nothing stored
  const n2 = await answered(codes[1]);
  const titleA = await pa.locator('#problem-title').textContent();
  if (!(await panel(pa, 'problem')) || !/another window/.test(titleA)) fail(`the window taken over was not told (problem panel: ${await panel(pa, 'problem')}, '${titleA}')`);
  if (n1 !== n0 + 1 || n2 !== n1) fail(`answers stored: ${n0} -> ${n1} (B answered) -> ${n2} (A, superseded, answered)`);
  // A takes the link back; B's next answer is refused and B is told.
  await pa.click('#problem-go');
  await waitPanel(pa, ['ask', 'break']);
  await waitPanel(pb, ['ask', 'break']);
  if (await panel(pb, 'ask')) {
    await answerNow(pb, '3');
    if (!(await panel(pb, 'problem'))) fail('B, taken over by A, was not told');
    if ((await answered(codes[1])) !== n2) fail('an answer from the superseded window B was stored');
  }
  console.log(`participant 2 in two contexts: B's answer stored (${n0} -> ${n1}), A's refused and A told; A took the link back`);

  // ---- blinding: one byte length per trial, no kind but training
  let pairs = 0;
  const seen = new Set();
  for (const t of trials) {
    if (t.done || seen.has(t.clip_a)) continue;
    seen.add(t.clip_a);
    if ('kind' in t || 'catch' in t) fail('the trial JSON tells the trial kind: ' + JSON.stringify(t));
    const la = (await (await fetch(base + t.clip_a)).arrayBuffer()).byteLength;
    const lb = (await (await fetch(base + t.clip_b)).arrayBuffer()).byteLength;
    if (la !== lb) fail(`trial ${t.index}: clips of ${la} and ${lb} bytes`);
    pairs++;
  }
  if (pairs < 6) fail(`only ${pairs} trials seen`);
  console.log(`blinding: ${pairs} trials, both clips of each the same byte length`);

  // ---- log lines and the status page
  for (const re of [/P001 answered trial \d+ \(\d+\/\d+\)/, /P001 completed the session/, /P002 restarted/,
                    /P002: an answer to trial \d+ from a superseded session refused/])
    if (!re.test(serverLog)) fail(`no log line ${re}:\n${serverLog}`);
  // a broken playback, for certain: participant 2's current trial answered with a playback hidden while the pair
  // played (what the page sends when the tab was switched away): stored, not counted, retaken (issue 28)
  const cur2 = await (await fetch(`${base}/api/${codes[1]}/trial`)).json();
  const hiddenBody = JSON.stringify({ trial: cur2.index, answer: 0, rt_ms: 900, telemetry: { play_ms: [150, 150],
    dropped: 0, frames: 24, hidden: 1, hidden_ms: 400, hidden_play: 1, fullscreen: 0 } });
  const hr = await fetch(`${base}/api/${codes[1]}/answer`, { method: 'POST', body: hiddenBody,
    headers: { 'content-type': 'application/json' } });
  if (hr.status !== 200) fail(`an answer with a hidden playback: HTTP ${hr.status} ${await hr.text()}`);
  const st = await browser.newPage();
  await st.goto(`${base}/status#${token}`);
  // conditions: rows, or the note why there are none yet (all test answers from observers the screening flags)
  await st.waitForFunction(() => document.querySelectorAll('#participants tbody tr').length === 2 &&
    (document.querySelectorAll('#conditions tbody tr').length > 0 || document.getElementById('note').textContent),
    null, { timeout: 20000 });
  const rows = await st.$$eval('#participants tbody tr', trs => trs.map(tr => [...tr.children].map(td => td.textContent)));
  await st.screenshot({ path: `${work}/status.png`, fullPage: true });
  if (rows[0][0] !== 'P001' || !rows[0][1].startsWith(`${acknowledged}/${acknowledged}`) || rows[0][2] !== 'yes')
    fail('status page, participant 1: ' + JSON.stringify(rows[0]));
  if (rows[1][0] !== 'P002' || Number(rows[1][4]) < 2) fail('status page, participant 2 (two restarts expected): ' + JSON.stringify(rows[1]));
  // P001 answered its catch trial "much better" or not: the page shows what the tally's screening says
  const obs = spawnSync(taslab, ['study', 'tally', '--db', db, '--out', `${work}/tally`, '--keep-flagged', '--bootstrap', '10'], { encoding: 'utf8' });
  const obsLines = require_file(`${work}/tally/observers.csv`).trim().split('\n'), fcol = obsLines[0].split(',').indexOf('flagged');
  const flaggedP1 = obsLines.some(l => l.startsWith('P001,') && l.split(',')[fcol] === '1');
  if (obs.status !== 0 || rows[0][5] !== (flaggedP1 ? 'yes' : 'no')) fail(`status page flags P001 '${rows[0][5]}', the tally: ${flaggedP1}`);
  // the P.910-crowd flags and the broken playbacks (issue 28): each participant's cells are the tally's observers.csv
  // (p910, broken) and the export's broken answers (planned trial, verdict), so the page never disagrees with them
  const head = obsLines[0].split(','), pcol = head.indexOf('p910'), bcol = head.indexOf('broken');
  const exp = spawnSync(taslab, ['study', 'export', '--db', db, '--out', `${work}/export.csv`], { encoding: 'utf8' });
  const ex = require_file(`${work}/export.csv`).trim().split('\n'), eh = ex[0].split(',');
  const [ep, et, eb, er] = ['participant', 'trial', 'broken', 'retake_of'].map(c => eh.indexOf(c));
  for (const [i, label] of ['P001', 'P002'].entries()) {
    const o = obsLines.find(l => l.startsWith(label + ',')).split(',');
    const wantFlags = o[pcol] ? o[pcol].split(';').join(', ') : 'none';
    const brokenRows = ex.slice(1).map(l => l.split(',')).filter(c => c[ep] === label && c[eb]);
    const wantBroken = brokenRows.length ? `${brokenRows.length} (${brokenRows.map(c =>
      `trial ${Number(c[er] !== '' ? c[er] : c[et]) + 1}: ${c[eb]}`).join(', ')})` : 'none';
    if (exp.status !== 0 || rows[i][6] !== wantFlags || rows[i][7] !== wantBroken || Number(o[bcol]) !== brokenRows.length)
      fail(`status page, ${label}: P.910 '${rows[i][6]}', broken '${rows[i][7]}'; the tally and export: '${wantFlags}', ` +
           `'${wantBroken}' (observers.csv broken ${o[bcol]})`);
  }
  if (!rows[1][7].includes(`trial ${cur2.index + 1}: hidden`)) fail(`status page, P002: the hidden playback is not listed: '${rows[1][7]}'`);
  console.log(`status page: P.910 flags '${rows[0][6]}', '${rows[1][6]}'; broken playbacks '${rows[0][7]}', '${rows[1][7]}'`);
  const anon = await fetch(`${base}/admin/status`);
  if (anon.status !== 401) fail(`/admin/status without the token: ${anon.status}`);
  const bare = await (await fetch(`${base}/status`)).text();
  if (/P001|tfr/.test(bare)) fail('the /status page itself carries data');
  console.log(`status page: ${rows.map(r => r.slice(0, 3).join(' ')).join('; ')} (screenshot status.png)`);
} catch (e) {
  console.error('study_recovery: ' + String(e.stack || e.message || e).split('\n').slice(0, 3).join('\n'));
  console.error('server log:\n' + serverLog.split('\n').slice(-20).join('\n'));
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
  if (server) server.kill('SIGTERM');
}
process.exit(status);
