// Builds the page's script bundle, deterministically: `node build.mjs [OUT]` (default: the
// copy the pgvol crate includes). The checks rebuild it from the lock file into a temporary
// file and compare it byte for byte with the committed one.

import { build } from 'esbuild';
import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const out = process.argv[2] ?? join(here, '../../crates/pgvol/src/view/viewer.min.js');
const three = JSON.parse(readFileSync(join(here, 'node_modules/three/package.json'), 'utf8'));

const result = await build({
  entryPoints: [join(here, 'src/main.js')],
  absWorkingDir: here,
  bundle: true,
  minify: true,
  format: 'iife',
  target: 'es2020',
  platform: 'browser',
  charset: 'utf8',
  legalComments: 'none',
  write: false,
  logLevel: 'warning',
});
let text = result.outputFiles[0].text;
// Inlined in a <script> element, the text must not close it: "<\/" reads the same in strings
// and regular expressions.
text = text.replace(/<\/(script)/gi, '<\\/$1');
const banner =
  `/* pgvol viewer, built from tools/viewer by build.mjs. Includes three.js ${three.version} ` +
  '(https://threejs.org, MIT License, Copyright 2010-2024 three.js authors). */\n';
writeFileSync(out, banner + text);
