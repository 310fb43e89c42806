// What the browser tests share: arguments, how chromium is started (headless, software
// WebGL2: SwiftShader through ANGLE, no GPU, no sandbox so that it runs as root in CI), pages
// that keep their console, and a driver's run.
import puppeteer from 'puppeteer-core';

/// --name value pairs over `defaults`.
export function parseArgs(argv, defaults = {}) {
  const args = { ...defaults };
  for (let i = 0; i < argv.length; i += 2) {
    if (!argv[i].startsWith('--') || i + 1 >= argv.length) throw new Error(`bad argument "${argv[i]}"`);
    args[argv[i].slice(2)] = argv[i + 1];
  }
  return args;
}

export function launchOptions(args) {
  return {
    executablePath: args.chromium || process.env.PIC_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--ignore-gpu-blocklist', '--disable-dev-shm-usage', '--force-device-scale-factor=1',
           '--no-first-run', '--no-default-browser-check'],
    defaultViewport: null,
  };
}

/// A new page of `owner` (a browser or a browser context) with `viewport`, its console
/// messages and page errors kept in page.logs.
export async function newPage(owner, viewport) {
  const page = await owner.newPage();
  await page.setViewport({ deviceScaleFactor: 1, ...viewport });
  page.logs = [];
  page.on('console', (m) => page.logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => page.logs.push(`page error: ${e.message}`));
  return page;
}

/// Starts chromium with launchOptions(args), runs `drive(browser)` and prints what it returns
/// as one JSON line, then exits 0; a failure's message goes to stderr with exit status 1.
/// Chromium is closed either way.
export async function runWithBrowser(args, drive) {
  const browser = await puppeteer.launch(launchOptions(args));
  let status = 0;
  try {
    console.log(JSON.stringify(await drive(browser)));
  } catch (error) {
    console.error(error.message);
    status = 1;
  } finally {
    await browser.close();
  }
  process.exit(status);
}
