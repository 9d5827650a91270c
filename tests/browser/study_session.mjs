// study_session.mjs — a simulated participant in Debian's Chromium (playwright-core): opens the participant
// link, answers every trial by keyboard (cycling 1..5), reloads the page midway and resumes, takes breaks.
// Then checks through the API and the token-protected export (Authorization: Bearer) that every trial was
// answered exactly once, and that the page only ever fetched clips by opaque names.
//   node study_session.mjs BASE_URL CODE ADMIN_TOKEN EXPECTED_TEST_TRIALS
import { chromium } from 'playwright-core';

const [base, code, token, expectedArg] = process.argv.slice(2);
const expected = Number(expectedArg);
const timer = setTimeout(() => { console.error('study_session: timed out'); process.exit(2); }, 180000);
let browser, status = 0;
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--autoplay-policy=no-user-gesture-required'],
  });
  const page = await browser.newPage();
  const log = [];
  page.on('console', m => log.push('console: ' + m.text()));
  page.on('pageerror', e => log.push('pageerror: ' + e.message));
  const clipUrls = [];                          // every clip the page fetched: opaque names only
  page.on('request', r => { const u = new URL(r.url()); if (u.pathname.startsWith('/clips/')) clipUrls.push(u.pathname); });
  globalThis.dumpState = async () => log.concat([await page.evaluate(() =>
    [...document.querySelectorAll('.panel')].map(x => x.id + ':' + getComputedStyle(x).display).join(' ') +
    ' progress=' + document.getElementById('progress').textContent + ' msg=' + document.getElementById('msg').textContent)]);
  const visible = id => page.locator('#' + id).isVisible();
  await page.goto(`${base}/p/${code}`);
  await page.click('#start');
  let answered = 0, reloaded = false, breaks = 0;
  for (let step = 0; step < 200; step++) {
    await page.waitForFunction(() => ['ask', 'break', 'done'].some(id =>
      getComputedStyle(document.getElementById(id)).display === 'block'), null, { timeout: 30000 });
    if (await visible('done')) break;
    if (await visible('break')) {
      breaks++;
      await page.click('#resume');
      await page.waitForFunction(() => getComputedStyle(document.getElementById('break')).display !== 'block');
      continue;
    }
    const before = await page.evaluate(() => document.body.dataset.trial);   // the trial's index (progress
    await page.keyboard.press(String(1 + (answered % 5)));                     // stays when it is retaken)
    answered++;
    await page.waitForFunction(b => document.body.dataset.trial !== b ||
      getComputedStyle(document.getElementById('done')).display === 'block', before, { timeout: 30000 });
    if (answered === 2 && !reloaded) {          // reload midway: the session resumes where it was
      reloaded = true;
      await page.reload();
      await page.click('#start');
    }
  }
  const state = await (await fetch(`${base}/api/${code}/trial`)).json();
  // The admin token travels in a header (never in the URL); without it the export is refused.
  const refused = (await fetch(`${base}/admin/export.csv?token=${token}`)).status;
  const csv = await (await fetch(`${base}/admin/export.csv`, { headers: { authorization: `Bearer ${token}` } })).text();
  const [head, ...lines] = csv.trim().split('\n');
  const cols = head.split(',');
  const all = lines.map(l => Object.fromEntries(l.split(',').map((v, i) => [cols[i], v])));   // every answered trial
  // A playback the server judged broken (issue 28: frames dropped on a loaded machine) is stored, not counted, and
  // comes again as a retake (retake_of = the planned trial) at most twice; training trials are not retaken. So: every
  // planned trial once, each retake of a planned trial whose earlier playback was broken, at most one counted answer
  // per planned trial, and the planned test trials are the design's.
  const planned = all.filter(r => r.retake_of === ''), retakes = all.filter(r => r.retake_of !== '');
  const counted = all.filter(r => r.broken === '');
  const tests = planned.filter(r => r.trial_type === 'test');
  const distinct = new Set(all.map(r => r.participant + ',' + r.trial));
  const once = new Set(counted.map(r => r.retake_of || r.trial));
  const badRetake = retakes.find(r => !all.some(o => (o.trial === r.retake_of || o.retake_of === r.retake_of) &&
                                                    Number(o.trial) < Number(r.trial) && o.broken !== ''));
  console.log(`answered ${answered} in the browser (reloaded once, ${breaks} break(s)), ${clipUrls.length} clip downloads; server: ${state.answered}/${state.total} done=${state.done}; export: ${all.length} rows (${all.length - counted.length} broken playbacks, ${retakes.length} retakes), ${tests.length} test trials, ${distinct.size} distinct`);
  if (!('broken' in (all[0] || {})) || !('retake_of' in (all[0] || {})) || planned.length !== state.total ||
      distinct.size !== all.length || once.size !== counted.length || badRetake) {
    console.error('the export does not hold every answered trial once'); status = 1;
  }
  if (refused !== 401) { console.error(`export with ?token= answered ${refused}, expected 401`); status = 1; }
  if (!clipUrls.length || clipUrls.some(u => !/^\/clips\/[0-9a-f]{32}\.webm$/.test(u))) { console.error('clip URLs not opaque: ' + clipUrls.join(' ')); status = 1; }
  if (!state.done || state.answered !== state.total || answered !== all.length || tests.length !== expected) {
    console.error(`expected ${expected} test trials, every one answered`); status = 1;
  }
} catch (e) {
  console.error('study_session: ' + String(e.message || e).split('\n')[0]);
  if (globalThis.dumpState) console.error((await globalThis.dumpState().catch(() => [])).join('\n'));
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
}
process.exit(status);
