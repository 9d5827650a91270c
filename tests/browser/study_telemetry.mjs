// study_telemetry.mjs — the participant page's playback telemetry in Debian's Chromium (playwright-core; issue 28).
// The page plays the trials as a participant's browser does; two trials are made broken from outside the page's code:
// the first one's page is hidden (visibilitychange, as when the participant switches tabs) while its first clip plays,
// the second one's first clip stalls (played at 1/16 speed: 16 x as long). Checks through the token-protected export:
// the playbacks that were left alone have plausible durations (at least 0.8 x the clip, at most the server's limit)
// and frame counts; the two broken trials are stored with their reasons, not counted, and came again later (the
// progress text unchanged meanwhile); the server holds every planned trial counted once.
//   node study_telemetry.mjs BASE CODE TOKEN CLIP_MS
import { chromium } from 'playwright-core';

const [base, code, token, clipArg] = process.argv.slice(2);
const clipMs = Number(clipArg), limit = 1.5 * clipMs + 1000;
const timer = setTimeout(() => { console.error('study_telemetry: timed out'); process.exit(2); }, 60000);
let browser, status = 0;
const fail = msg => { console.error('FAIL ' + msg); status = 1; };
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--autoplay-policy=no-user-gesture-required'],
  });
  const page = await browser.newPage();
  const log = [];
  page.on('pageerror', e => log.push('pageerror: ' + e.message));
  await page.goto(`${base}/p/${code}`);
  // The disturbances, armed from the test: the next clip to play is played hidden, or stalls.
  await page.evaluate(() => {
    const play = HTMLMediaElement.prototype.play;
    HTMLMediaElement.prototype.play = function () {
      if (window.__hide) {
        window.__hide = false;
        Object.defineProperty(document, 'visibilityState', { configurable: true, get: () => 'hidden' });
        document.dispatchEvent(new Event('visibilitychange'));
        setTimeout(() => { delete document.visibilityState; document.dispatchEvent(new Event('visibilitychange')); }, 60);
      }
      if (window.__slow) {
        window.__slow = false;
        this.defaultPlaybackRate = this.playbackRate = 1 / 16;
      }
      return play.call(this);
    };
    window.__hide = true;                         // trial 0
  });
  await page.click('#start');
  const progress = [];
  let answered = 0;
  for (let step = 0; step < 20; step++) {
    await page.waitForFunction(() => ['ask', 'done'].some(id =>
      getComputedStyle(document.getElementById(id)).display === 'block'), null, { timeout: 20000 });
    if (await page.locator('#done').isVisible()) break;
    const trial = await page.evaluate(() => document.body.dataset.trial);
    progress.push(trial + ':' + await page.locator('#progress').textContent());
    if (trial === '0') await page.evaluate(() => { window.__slow = true; });   // trial 1 plays right after
    await page.keyboard.press(String(1 + (answered % 5)));
    answered++;
    await page.waitForFunction(b => document.body.dataset.trial !== b, trial, { timeout: 20000 });
  }
  const text = await (await fetch(`${base}/admin/export.csv`, { headers: { authorization: `Bearer ${token}` } })).text();
  const [head, ...lines] = text.trim().split('\n');
  const cols = head.split(',');
  const rows = lines.map(r => Object.fromEntries(r.split(',').map((v, i) => [cols[i], v])));
  const state = await (await fetch(`${base}/api/${code}/trial`)).json();
  const ok = rows.filter(r => r.broken === '');
  for (const r of rows)
    console.log(`trial ${r.trial} (${r.trial_type}${r.retake_of ? ', retake of ' + r.retake_of : ''}): played ${r.play_a_ms} + ${r.play_b_ms} ms, ${r.dropped_frames}/${r.total_frames} frames dropped, hidden ${r.hidden}x (${r.hidden_play} during playback, ${r.hidden_ms} ms), full screen ${r.fullscreen}${r.broken ? ' -> broken: ' + r.broken : ''}`);
  console.log('progress shown: ' + progress.join(' | '));
  const t0 = rows.find(r => r.trial === '0'), t1 = rows.find(r => r.trial === '1');
  if (!t0 || !t0.broken.includes('hidden') || Number(t0.hidden_play) < 1) fail('trial 0 (hidden while playing) not judged broken');
  if (!t1 || !t1.broken.includes('long') || !(Number(t1.play_a_ms) > limit)) fail('trial 1 (stalled) not judged broken');
  if (!rows.some(r => r.retake_of === '0') || !rows.some(r => r.retake_of === '1')) fail('the broken trials did not come again');
  if (!progress[1] || !progress[1].endsWith('Trial 1 of 3')) fail('the progress moved on after a broken trial: ' + progress[1]);
  for (const r of ok) {
    const a = Number(r.play_a_ms), b = Number(r.play_b_ms), d = Number(r.dropped_frames), f = Number(r.total_frames);
    if (!(a >= 0.8 * clipMs && a <= limit && b >= 0.8 * clipMs && b <= limit)) fail(`trial ${r.trial}: implausible durations ${a}, ${b} ms`);
    if (!(f > 0 && f <= 2 * Math.ceil(clipMs * 60 / 1000) + 4 && d <= f)) fail(`trial ${r.trial}: implausible frames ${d}/${f}`);
    if (r.hidden !== '0' || r.hidden_ms !== '0') fail(`trial ${r.trial}: hidden ${r.hidden} times`);
  }
  if (!state.done || state.answered !== 3 || state.total !== 3) fail(`server: ${JSON.stringify(state)}`);
  const planned = new Set(ok.map(r => r.retake_of || r.trial));   // each planned trial counted once at most
  if (planned.size !== ok.length) fail(`${ok.length} counted answers for ${planned.size} planned trials`);
} catch (e) {
  console.error('study_telemetry: ' + String(e.message || e).split('\n')[0]);
  console.error(log.join('\n'));
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
}
process.exit(status);
