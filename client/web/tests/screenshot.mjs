// Opens one view of a session in headless chromium (SwiftShader WebGL2 through ANGLE) and
// saves the canvas as PNG once the page has drawn a version's final state:
//   node screenshot.mjs --url URL --out FILE.png [--version N] [--timeout-s S]
//                       [--chromium PATH] [--page 1]
// (--page 1: the whole page, panel and gizmos included, not the canvas alone). Prints one JSON
// line: the page's window.pic report (versions, sizes, times). Exit status 1 with the page's
// error or a timeout on stderr.
import { newPage, parseArgs, runWithBrowser } from './browser.mjs';

const args = parseArgs(process.argv.slice(2), { version: '1', 'timeout-s': '120' });
if (!args.url || !args.out) {
  console.error('usage: node screenshot.mjs --url URL --out FILE.png [--version N] [--timeout-s S]');
  process.exit(2);
}
await runWithBrowser(args, async (browser) => {
  const size = /[?&]size=(\d+)x(\d+)/.exec(args.url);
  const page = await newPage(browser, { width: size ? Number(size[1]) : 800,
                                        height: size ? Number(size[2]) : 600 });
  await page.goto(args.url);
  const version = Number(args.version);
  await page.waitForFunction(
    (v) => window.pic && (window.pic.state === 'error' ||
                          (window.pic.drawnVersion >= v && window.pic.drawnPart === 0)),
    { timeout: Number(args['timeout-s']) * 1000, polling: 50 }, version);
  const report = await page.evaluate(() => {
    const { stream, panel, ...rest } = window.pic;
    return rest;
  });
  if (report.state === 'error') throw new Error(`the page failed: ${report.error}\n${page.logs.join('\n')}`);
  if (args.page) {
    await page.screenshot({ path: args.out });
  } else {
    const canvas = await page.$('canvas');
    await canvas.screenshot({ path: args.out, omitBackground: false });
  }
  return report;
});
