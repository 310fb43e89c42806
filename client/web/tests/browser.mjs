// What the browser tests share: arguments and how chromium is started (headless, software
// WebGL2: SwiftShader through ANGLE, no GPU, no sandbox so that it runs as root in CI).

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
