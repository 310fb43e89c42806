// Two browsers on one session, driven as reviewers use them:
//   node session.mjs --editor URL --viewer URL [--timeout-s S]
// (URLs of the page with ui on; the editor's carrying the viewer token as `viewer`). The
// editor's share links: the view's with the viewer token, the editing one with its own; a
// page whose `viewer` is not the session's viewer token refuses to start. The editor drags
// its first light's gizmo; the viewer must
// draw the version that carries it and show the light where the editor put it. The viewer's
// gizmos do not drag, and a light change it sends is refused. The viewer's connection is then
// dropped; it connects again and draws the editor's next drag. Prints one JSON line of what
// happened; exit status 1 with the reason on stderr.
import { newPage, parseArgs, runWithBrowser } from './browser.mjs';

const args = parseArgs(process.argv.slice(2), { 'timeout-s': '120' });
const timeout = Number(args['timeout-s']) * 1000;

/// `browser`'s page at `url` once it has drawn, or failed (`window.pic.error`, thrown unless
/// `failing`).
async function open(browser, url, failing = false) {
  const page = await newPage(browser, { width: 960, height: 600 });
  await page.goto(url);
  await page.waitForFunction(() => window.pic && (window.pic.state !== 'loading'), { timeout, polling: 50 });
  const error = await page.evaluate(() => window.pic.error);
  if (error && !failing) throw new Error(`${url}: ${error}\n${page.logs.join('\n')}`);
  return page;
}

/// Drags the first light's gizmo by (dx, dy) pixels in steps, as a mouse does.
async function drag(page, dx, dy) {
  const gizmo = await page.waitForSelector('.gizmo', { timeout });
  const box = await gizmo.boundingBox();
  const x = box.x + box.width / 2, y = box.y + box.height / 2;
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let i = 1; i <= 8; ++i) await page.mouse.move(x + dx * i / 8, y + dy * i / 8);
  await page.mouse.up();
  return page.evaluate(() => window.pic.panel.lights().lights[0].id);
}

/// Waits until the editor's last edit was accepted (a version after `after`) and `page` drew that version; the light
/// `id` as `page` then has it.
async function drawnEdit(editor, page, id, after = 0) {
  await editor.waitForFunction((a) => !window.pic.panel.inFlight && !window.pic.panel.pending &&
                               window.pic.panel.awaited > a, { timeout, polling: 50 }, after);
  const version = await editor.evaluate(() => window.pic.panel.awaited);
  await page.waitForFunction((v) => window.pic.drawnVersion >= v, { timeout, polling: 50 }, version);
  const light = await page.evaluate((lightId) => window.pic.lights.lights.find((l) => l.id === lightId), id);
  return { version, light };
}

await runWithBrowser(args, async (browser) => {
  const out = {};
  const editor = await open(browser, args.editor);
  const viewer = await open(browser, args.viewer);
  out.editorRole = await editor.evaluate(() => window.pic.role);
  out.viewerRole = await viewer.evaluate(() => window.pic.role);
  const shareLinks = (page) => page.evaluate(() => ({
    view: window.pic.panel.shareUrl(false), edit: window.pic.panel.shareUrl(true),
    label: document.getElementById('share').textContent,
    editButton: document.getElementById('share-edit') !== null,
  }));
  out.editorShare = await shareLinks(editor);
  out.viewerShare = await shareLinks(viewer);
  const wrongViewer = new URL(args.editor);
  wrongViewer.searchParams.set('viewer', wrongViewer.searchParams.get('token'));
  const refused = await open(browser, wrongViewer.href, true);
  out.wrongViewerError = await refused.evaluate(() => window.pic.error);
  await refused.close();
  const before = await viewer.evaluate(() => window.pic.lights.lights[0]);
  const id = await drag(editor, 80, 30);
  const seen = await drawnEdit(editor, viewer, id);
  const editorLight = await editor.evaluate((lightId) => window.pic.panel.lights().lights.find((l) => l.id === lightId), id);
  Object.assign(out, { light: id, before, version: seen.version, viewerLight: seen.light, editorLight });

  // The viewer: its gizmo does not move the light, and a set it sends is refused.
  const versionBefore = await viewer.evaluate(() => window.pic.version);
  await drag(viewer, 60, 0);
  out.viewerDragRequests = await viewer.evaluate(() => window.pic.panel.awaited);
  out.viewerRefusal = await viewer.evaluate(async () => {
    try {
      await window.pic.panel.api.setLights(JSON.stringify({ lights: [] }));
      return { status: 200 };
    } catch (error) {
      return { status: error.status, message: error.message };
    }
  });
  out.viewerVersionAfterRefusal = await viewer.evaluate(() => window.pic.version);
  out.versionBeforeRefusal = versionBefore;

  // A dropped connection: the viewer connects again and draws the next change.
  await viewer.evaluate(() => window.pic.stream.socket.close());
  await viewer.waitForFunction(() => window.pic.stream.connections >= 2, { timeout, polling: 50 });
  await drag(editor, -40, 40);
  const resumed = await drawnEdit(editor, viewer, id, seen.version);
  out.resumed = { version: resumed.version, light: resumed.light,
                  connections: await viewer.evaluate(() => window.pic.stream.connections) };
  out.editorLightAfter = await editor.evaluate((lightId) => window.pic.panel.lights().lights.find((l) => l.id === lightId), id);
  return out;
});
