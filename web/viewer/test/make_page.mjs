// Usage: node test/make_page.mjs FIXTURE.glb OUT.html
// Writes a minimal self-contained page the way the Rust exporter does:
// the glb as base64 in a data <script>, dist/viewer.js inlined as a classic script.
import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const [glbPath, outPath] = process.argv.slice(2);
if (!glbPath || !outPath) {
  console.error('usage: node test/make_page.mjs FIXTURE.glb OUT.html');
  process.exit(2);
}
const bundlePath = join(dirname(fileURLToPath(import.meta.url)), '..', 'dist', 'viewer.js');
const bundle = readFileSync(bundlePath, 'utf8');
// Inline script text must not close the element early nor open an HTML comment.
if (/<\/script|<!--/i.test(bundle)) {
  console.error(`make_page: ${bundlePath} contains "</script" or "<!--"; cannot inline it`);
  process.exit(1);
}
const b64 = readFileSync(glbPath).toString('base64');

const html = `<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>visage viewer test page</title>
</head>
<body style="font-family:sans-serif;margin:16px">
<h1 style="font-size:18px">visage viewer test page</h1>
<div id="visage-viewer"></div>
<script id="visage-glb" type="application/octet-stream">${b64}</script>
<script>${bundle}</script>
</body>
</html>
`;
writeFileSync(outPath, html);
console.log(`${outPath}: ${html.length} bytes`);
