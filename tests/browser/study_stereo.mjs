// study_stereo.mjs — the participant page of a stereo study in Chromium (playwright-core): the trial API says
// "display": "stereo"; while a clip plays the video spans the page's width (both eyes side by side, 2:1 here) and
// the "left eye" / "right eye" labels sit under its halves; a screenshot is taken mid-clip.
//   node study_stereo.mjs BASE_URL CODE SCREENSHOT.png
import { chromium } from 'playwright-core';

const [base, code, shot] = process.argv.slice(2);
const timer = setTimeout(() => { console.error('study_stereo: timed out'); process.exit(2); }, 60000);
let browser, status = 0;
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--autoplay-policy=no-user-gesture-required'],
  });
  const page = await browser.newPage({ viewport: { width: 960, height: 540 } });
  const errors = [];
  page.on('pageerror', e => errors.push(e.message));
  await page.goto(`${base}/p/${code}`);
  await page.click('#start');
  // mid-clip: the video is playing and has advanced a little
  await page.waitForFunction(() => { const v = document.getElementById('video');
    return v.style.display === 'block' && !v.paused && v.currentTime > 0.2; }, null, { timeout: 30000 });
  const st = await page.evaluate(() => {
    const v = document.getElementById('video'), r = v.getBoundingClientRect();
    const spans = [...document.querySelectorAll('#eyes span')].map(s => s.getBoundingClientRect());
    return { w: r.width, h: r.height, vw: v.videoWidth, vh: v.videoHeight, eyes: getComputedStyle(document.getElementById('eyes')).display,
             l: spans[0].left + spans[0].width / 2, r: spans[1].left + spans[1].width / 2, page: innerWidth };
  });
  await page.screenshot({ path: shot });
  const trial = await (await fetch(`${base}/api/${code}/trial`)).json();
  console.log(`display=${trial.display} clip ${st.vw}x${st.vh} shown ${Math.round(st.w)}x${Math.round(st.h)} in ${st.page}; labels ${st.eyes} at ${Math.round(st.l)}, ${Math.round(st.r)}`);
  if (trial.display !== 'stereo') { console.error('trial API: display is not stereo'); status = 1; }
  if (st.vw !== 96 || st.vh !== 32) { console.error('the clip is not both 48x32 eyes side by side'); status = 1; }
  if (Math.abs(st.w - st.page) > 1) { console.error('the side-by-side clip does not span the page'); status = 1; }
  if (st.eyes !== 'block' || Math.abs(st.l - st.page / 4) > 2 || Math.abs(st.r - 3 * st.page / 4) > 2) {
    console.error('the eye labels are not under the halves'); status = 1;
  }
  if (errors.length) { console.error('page errors: ' + errors.join('; ')); status = 1; }
} catch (e) {
  console.error('study_stereo: ' + String(e.message || e).split('\n')[0]);
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
}
process.exit(status);
