// study_adaptive.mjs — the adaptive design through the participant page in Debian's Chromium (playwright-core;
// issue 28): the participant answers every trial by keyboard and reloads the page at the third trial (the same trial
// must come back, with the same clips); the token-protected export must hold every trial once, the 4 planned test
// trials at rendered levels of T and the catch trial, each counted once unless its playback broke three times. Then the same answers (and the page's telemetry, so that the server
// judges the playbacks alike) go to a second study of the same design and seed through the API alone, without a
// page: its export must list the same trials with the same T — the server chose them, from the seed and the answers.
//   node study_adaptive.mjs BASE CODE TOKEN REPLAY_BASE REPLAY_CODE REPLAY_TOKEN
import { chromium } from 'playwright-core';

const [base, code, token, base2, code2, token2] = process.argv.slice(2);
const timer = setTimeout(() => { console.error('study_adaptive: timed out'); process.exit(2); }, 60000);
let browser, status = 0;
const fail = msg => { console.error('FAIL ' + msg); status = 1; };
const exportCsv = async (b, t) => {
  const text = await (await fetch(`${b}/admin/export.csv`, { headers: { authorization: `Bearer ${t}` } })).text();
  const [head, ...rows] = text.trim().split('\n');
  const cols = head.split(',');
  return rows.map(r => Object.fromEntries(r.split(',').map((v, i) => [cols[i], v])));
};
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--autoplay-policy=no-user-gesture-required'],
  });
  const page = await browser.newPage();
  const log = [], clips = [];
  page.on('pageerror', e => log.push('pageerror: ' + e.message));
  page.on('request', r => { const u = new URL(r.url()); if (u.pathname.startsWith('/clips/')) clips.push(u.pathname); });
  const shown = () => page.waitForFunction(() => ['ask', 'break', 'done'].some(id =>
    getComputedStyle(document.getElementById(id)).display === 'block'), null, { timeout: 20000 });
  await page.goto(`${base}/p/${code}`);
  await page.click('#start');
  let answered = 0, reloaded = false;
  for (let step = 0; step < 40; step++) {
    await shown();
    if (await page.locator('#done').isVisible()) break;
    if (await page.locator('#break').isVisible()) { await page.click('#resume'); continue; }
    const trial = await page.evaluate(() => document.body.dataset.trial);
    if (answered === 2 && !reloaded) {    // reload at the third trial: it comes back, with its clips (its T kept)
      reloaded = true;
      const before = clips.slice(-2).join(' ');
      await page.reload();
      await page.click('#start');
      await shown();
      const again = await page.evaluate(() => document.body.dataset.trial);
      if (again !== trial) fail(`after the reload trial ${again} was shown, not ${trial}`);
      if (clips.slice(-2).join(' ') !== before) fail(`after the reload the clips were ${clips.slice(-2)}, not ${before}`);
    }
    await page.keyboard.press(String([5, 1, 4, 2, 3][answered % 5]));
    answered++;
    await page.waitForFunction(b => document.body.dataset.trial !== b, trial, { timeout: 20000 });
  }
  const rows = await exportCsv(base, token);
  const counted = rows.filter(r => r.broken === '');
  const tests = counted.filter(r => r.trial_type === 'test');
  const Ts = tests.map(r => r.T);
  console.log(`answered ${answered} in the browser (reloaded once); export: ${rows.length} rows, ${rows.length - counted.length} broken playbacks, test trials at T = ${Ts.join(', ')}`);
  if (new Set(rows.map(r => r.trial)).size !== rows.length || rows.length !== answered) fail('the export does not hold every answer once');
  // The plan: 4 test trials and 1 catch trial. A playback the server judged broken (headless Chromium drops frames
  // on a loaded machine) is retaken at most twice, so each planned trial has at most one counted answer, after
  // only broken ones, or three broken answers and none counted.
  const planned = rows.filter(r => r.retake_of === '');
  if (planned.filter(r => r.trial_type === 'test').length !== 4 || planned.filter(r => r.trial_type === 'catch').length !== 1)
    fail('expected 4 planned test trials and 1 catch trial');
  let countedPlans = 0;
  for (const p of planned) {
    const tries = rows.filter(r => r.trial === p.trial || r.retake_of === p.trial);
    const ok = tries.filter(r => r.broken === '');
    if (tries.some(r => r.trial_type !== p.trial_type)) fail(`trial ${p.trial}: a retake of another kind`);
    if (ok.length > 1 || (ok.length === 1 && ok[0] !== tries[tries.length - 1]))
      fail(`trial ${p.trial}: counted answers ${ok.map(r => r.trial)} among ${tries.map(r => r.trial)}`);
    else if (ok.length === 0 && tries.length !== 3) fail(`trial ${p.trial}: ${tries.length} broken answers and no retake left`);
    countedPlans += ok.length;
  }
  if (countedPlans !== counted.length) fail('a counted answer outside the planned trials and their retakes');
  if (tests.length === 0) fail('no test trial counted: every playback broken (a machine too loaded for the page?)');
  if (Ts.some(t => !['2', '4', '8', '16'].includes(t))) fail('a T that is not a rendered level');
  if (rows.some(r => r.play_a_ms === '' || r.total_frames === '')) fail('an answer from the page without telemetry');
  // The replay: the same answers and telemetry, through the API alone.
  const session = (await (await fetch(`${base2}/api/${code2}/session`, { method: 'POST', body: '{}' })).json()).session;
  for (const r of rows) {
    const t = await (await fetch(`${base2}/api/${code2}/trial`)).json();
    if (String(t.index) !== r.trial) { fail(`replay: the server offered trial ${t.index}, the page had answered ${r.trial}`); break; }
    const n = k => Number(r[k]);
    const body = { trial: t.index, answer: n('answer'), rt_ms: n('rt_ms'), session, telemetry: {
      play_ms: [n('play_a_ms'), n('play_b_ms')], dropped: n('dropped_frames'), frames: n('total_frames'), hidden: n('hidden'),
      hidden_ms: n('hidden_ms'), hidden_play: n('hidden_play'), fullscreen: n('fullscreen') } };
    const a = await fetch(`${base2}/api/${code2}/answer`, { method: 'POST', headers: { 'content-type': 'application/json' },
                                                           body: JSON.stringify(body) });
    if (a.status !== 200) { fail(`replay: answer to trial ${t.index}: ${a.status} ${await a.text()}`); break; }
  }
  const key = r => [r.trial, r.trial_type, r.method, r.T, r.ref_first, r.answer, r.broken, r.retake_of].join(',');
  const replay = await exportCsv(base2, token2);
  if (replay.map(key).join('\n') !== rows.map(key).join('\n'))
    fail(`the replay's trials differ:\n${rows.map(key).join('\n')}\nreplay:\n${replay.map(key).join('\n')}`);
  else console.log(`replay through the API: the same ${replay.length} trials, the same T`);
} catch (e) {
  console.error('study_adaptive: ' + String(e.message || e).split('\n')[0]);
  console.error(log.join('\n'));
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
}
process.exit(status);
