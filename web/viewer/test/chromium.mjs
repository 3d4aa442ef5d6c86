// Headless Chromium's flags for the page checks (check_report.mjs, check_live.mjs).
export const CHROMIUM_ARGS = [
  '--headless',
  '--no-sandbox', // running as root in a container
  '--disable-gpu', // no GPU here: WebGL comes from SwiftShader instead
  '--use-angle=swiftshader', // ANGLE on the SwiftShader CPU backend
  '--enable-unsafe-swiftshader', // Chromium ≥ 139 refuses SwiftShader WebGL without it
  '--disable-quic',
  '--no-first-run',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
];
