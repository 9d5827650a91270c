// clip_fidelity.mjs — does a taslab clip reach the screen bit-exact in Debian's Chromium?
// Serves the clip and its PNG frames from a local HTTP server with Range support (127.0.0.1, ephemeral
// port), loads them in headless Chromium (playwright-core, /usr/bin/chromium), seeks the <video> to each
// chosen frame, draws it to a canvas and compares every pixel with the PNG drawn the same way.
// Prints the max |difference| per frame; exits 1 if any is non-zero, 2 on setup errors.
//   node clip_fidelity.mjs CLIP.webm FRAMES_DIR FPS FIRST_FRAME FRAME[,FRAME...]
import { createServer } from 'node:http';
import { promises as fs, statSync, createReadStream } from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const [clip, framesDir, fpsArg, firstArg, list] = process.argv.slice(2);
if (!list) {
  console.error('usage: node clip_fidelity.mjs CLIP.webm FRAMES_DIR FPS FIRST_FRAME FRAME[,FRAME...]');
  process.exit(2);
}
const fps = Number(fpsArg), first = Number(firstArg), frames = list.split(',').map(Number);

const page = `<!doctype html><meta charset="utf-8"><body>
<video id="v" src="/clip.webm" muted playsinline preload="auto"></video>
<script>
async function grab(src) { // draws an image or the current video frame, returns its RGBA bytes
  const c = document.createElement('canvas');
  c.width = src.videoWidth || src.naturalWidth; c.height = src.videoHeight || src.naturalHeight;
  const g = c.getContext('2d', { willReadFrequently: true, colorSpace: 'srgb' });
  g.drawImage(src, 0, 0);
  return g.getImageData(0, 0, c.width, c.height).data;
}
window.compare = async (frame, index, fps) => {
  const v = document.getElementById('v');
  if (v.readyState < 2) await new Promise(r => v.addEventListener('loadeddata', r, { once: true }));
  await new Promise(r => { v.addEventListener('seeked', r, { once: true }); v.currentTime = (index + 0.5) / fps; });
  await new Promise(r => setTimeout(r, 100)); // let the compositor take the seeked frame
  const img = new Image(); img.src = '/frames/' + String(frame).padStart(6, '0') + '.png';
  await img.decode();
  const a = await grab(v), b = await grab(img);
  if (a.length !== b.length) return { error: 'size ' + v.videoWidth + 'x' + v.videoHeight + ' vs ' + img.naturalWidth + 'x' + img.naturalHeight };
  let max = 0, count = 0;
  for (let i = 0; i < a.length; i++) { const d = Math.abs(a[i] - b[i]); if (d) count++; if (d > max) max = d; }
  return { max, count };
};
</script>`;

// Minimal static server with single-range support (what <video> needs to seek).
const server = createServer(async (req, res) => {
  const url = new URL(req.url, 'http://localhost');
  let file;
  if (url.pathname === '/') { res.writeHead(200, { 'content-type': 'text/html' }); return res.end(page); }
  if (url.pathname === '/clip.webm') file = clip;
  else if (/^\/frames\/\d{6}\.png$/.test(url.pathname)) file = path.join(framesDir, path.basename(url.pathname));
  else { res.writeHead(404); return res.end(); }
  let size;
  try { size = statSync(file).size; } catch { res.writeHead(404); return res.end(); }
  const type = file.endsWith('.webm') ? 'video/webm' : 'image/png';
  const m = /^bytes=(\d*)-(\d*)$/.exec(req.headers.range || '');
  if (m) {
    const start = m[1] ? Number(m[1]) : size - Number(m[2]);
    const end = m[1] && m[2] ? Math.min(Number(m[2]), size - 1) : size - 1;
    if (start > end || start >= size) { res.writeHead(416, { 'content-range': `bytes */${size}` }); return res.end(); }
    res.writeHead(206, { 'content-type': type, 'accept-ranges': 'bytes', 'content-length': end - start + 1,
                         'content-range': `bytes ${start}-${end}/${size}` });
    createReadStream(file, { start, end }).pipe(res);
  } else {
    res.writeHead(200, { 'content-type': type, 'accept-ranges': 'bytes', 'content-length': size });
    createReadStream(file).pipe(res);
  }
});

let browser, status = 0;
const timer = setTimeout(() => { console.error('clip_fidelity: timed out'); process.exit(2); }, 120000);
try {
  await fs.access(clip);
  await new Promise(r => server.listen(0, '127.0.0.1', r));
  const port = server.address().port;
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--force-color-profile=srgb', '--autoplay-policy=no-user-gesture-required'],
  });
  const tab = await browser.newPage();
  await tab.goto(`http://127.0.0.1:${port}/`);
  if (process.env.DEBUG) {
    tab.on('console', m => console.log('page:', m.text()));
    console.log(await tab.evaluate(() => { const v = document.getElementById('v');
      return JSON.stringify({ can: v.canPlayType('video/webm; codecs="vp9"'), rs: v.readyState, err: v.error && v.error.message, ns: v.networkState }); }));
  }
  for (const f of frames) {
    const r = await tab.evaluate(([frame, index, fps]) => window.compare(frame, index, fps), [f, f - first, fps]);
    if (r.error) { console.log(`frame ${f}: ${r.error}`); status = 1; continue; }
    console.log(`frame ${f}: max |difference| ${r.max} (${r.count} channel values differ)`);
    if (r.max !== 0) status = 1;
  }
} catch (e) {
  console.error('clip_fidelity: ' + String(e.message || e).split('\n')[0]);
  status = 2;
} finally {
  clearTimeout(timer);
  if (browser) await browser.close();
  server.close();
}
process.exit(status);
