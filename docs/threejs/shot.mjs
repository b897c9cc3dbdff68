// node shot.mjs LEVEL.glb OUT.png [WIDTHxHEIGHT] [EYE] [TARGET]: serves this folder and LEVEL.glb on
// localhost, opens index.html in Debian's Chromium (headless, WebGL on SwiftShader) and saves the canvas.
// Needs `npm ci` here and Debian's chromium package.
import fs from 'fs';
import http from 'http';
import path from 'path';
import { fileURLToPath } from 'url';
import { chromium } from 'playwright-core';

const [level, out, size = '640x400', eye = '1.5,5,7.5', target = '-0.5,0.6,-0.5'] = process.argv.slice(2);
const [width, height] = size.split('x').map(Number);
const here = path.dirname(fileURLToPath(import.meta.url));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.glb': 'model/gltf-binary' };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
  if (url === '/favicon.ico') { res.writeHead(204); res.end(); return; }
  const file = url === '/level.glb' ? path.resolve(level) : path.join(here, path.normalize(url));
  fs.readFile(file, (err, data) => {
    if (err) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] ?? 'application/octet-stream' });
    res.end(data);
  });
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
try {
  const page = await browser.newPage({ viewport: { width, height } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { console.log('page:', m.text()); if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?file=level.glb&eye=${eye}&target=${target}`);
  await page.waitForFunction(() => document.title === 'done' || undefined, null, { timeout: 60000 })
    .catch(() => { throw new Error(`the page did not finish: ${errors.join('; ')}`); });
  if (errors.length) throw new Error(errors.join('; '));
  await page.locator('canvas').screenshot({ path: out });
  console.log(`wrote ${out} (${width}x${height}) from ${level}`);
} finally {
  await browser.close();
  server.close();
}
