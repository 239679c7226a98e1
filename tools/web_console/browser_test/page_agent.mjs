// The web console's page in Debian's Chromium (headless), driven by playwright-core for
// a test: tools/web_console/test/web_browser_test.cpp starts the stack and rover_web on a
// private bus, runs this script, and sends it one JSON request a line on stdin; each
// answer is one JSON line on stdout ({"ok":true,...} or {"ok":false,"error":"..."}).
// The test, which hears the bus, compares what this script reads off the page with it.
//
//   {"op":"open","url":U}                load the page; answers once it says "live"
//   {"op":"read","points":[[x,y],...]}   what the page shows (the data- attributes app.js
//                                        keeps on the elements it fills) and, drawn in the
//                                        same frame, the map canvas's colour at each site
//                                        point (x north, y east), through the page's own view
//   {"op":"fill","id":ID,"text":T}       type into an input or the sequence's text area
//   {"op":"click","id":ID}               click a button; answers with the page's result line
//   {"op":"screenshot","path":P}         the whole page as a PNG
//   {"op":"quit"}
//
// usage: node page_agent.mjs MODULES_DIR CHROMIUM
//   MODULES_DIR holds node_modules/playwright-core (npm ci of this folder's package.json);
//   CHROMIUM is the browser to drive (/usr/bin/chromium).
import { createRequire } from 'node:module';
import path from 'node:path';
import readline from 'node:readline';

const [modulesDir, executablePath] = process.argv.slice(2);
const say = (obj) => process.stdout.write(JSON.stringify(obj) + '\n');
let chromium;
try {
  ({ chromium } = createRequire(path.join(path.resolve(modulesDir), 'package.json'))('playwright-core'));
} catch (e) {
  say({ ok: false, error: 'playwright-core not found under ' + modulesDir + ' (npm ci there): ' + e.message });
  process.exit(3);
}

const browser = await chromium.launch({ executablePath, headless: true, timeout: 60000 });
const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
const pageErrors = [];
page.on('pageerror', (e) => pageErrors.push(String(e)));
say({ ok: true, browser: browser.version() });

// Everything the test compares, read in one go inside the page (no redraw in between).
function readPage(points) {
  const $ = (id) => document.getElementById(id);
  const map = $('map');
  const num = (v) => (v === undefined || v === '' ? null : Number(v));
  const view = map.dataset.view ? JSON.parse(map.dataset.view) : null;
  const ctx = map.getContext('2d');
  const colours = (points || []).map(([x, y]) => {
    if (!view) return null;
    // The page's own transform (app.js drawMap): north up, east right.
    const px = Math.round(view.W / 2 + (y - view.cx) * view.scale);
    const py = Math.round(view.H / 2 - (x - view.cy) * view.scale);
    if (px < 0 || py < 0 || px >= map.width || py >= map.height) return null;
    return Array.from(ctx.getImageData(px, py, 1, 1).data);
  });
  const pose = $('pose').dataset;
  return {
    conn: $('conn').textContent,
    state: $('seqhead').dataset.state || null,
    submission_id: $('seqhead').dataset.submission || null,
    pose: pose.utime ? { x: num(pose.x), y: num(pose.y), z: num(pose.z), utime: pose.utime } : null,
    step_count: num($('steps').dataset.count),
    step_rows: $('steps').tBodies[0].rows.length,
    zones: map.dataset.zones ? map.dataset.zones.split(',') : [],
    goal: map.dataset.goal ? map.dataset.goal.split(' ').map(Number) : null,
    result: $('result').textContent,
    banner: $('banner').hidden ? '' : $('banner').textContent,
    colours,
  };
}

async function handle(req) {
  switch (req.op) {
    case 'open':
      await page.goto(req.url, { timeout: 30000 });
      await page.waitForFunction(() => document.getElementById('conn').textContent === 'live', null, { timeout: 30000 });
      return {};
    case 'read':
      return { page: await page.evaluate(readPage, req.points || []) };
    case 'fill':
      await page.fill('#' + req.id, req.text, { timeout: 10000 });
      return {};
    case 'click': {
      // The page writes '...' when it sends, then the answer's status and text.
      await page.click('#' + req.id, { timeout: 10000 });
      await page.waitForFunction(() => {
        const t = document.getElementById('result').textContent;
        return t !== '' && t !== '...';
      }, null, { timeout: 15000 });
      return { result: await page.textContent('#result') };
    }
    case 'screenshot':
      await page.screenshot({ path: req.path, fullPage: true });
      return {};
    case 'quit':
      return null;
    default:
      throw new Error('unknown op ' + JSON.stringify(req.op));
  }
}

const lines = readline.createInterface({ input: process.stdin });
for await (const line of lines) {
  let answer;
  try {
    answer = await handle(JSON.parse(line));
    if (answer === null) break;
    say({ ok: true, page_errors: pageErrors.splice(0), ...answer });
  } catch (e) {
    say({ ok: false, error: String(e.message || e).split('\n')[0] });
  }
}
await browser.close();
