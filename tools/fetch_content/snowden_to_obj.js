// Decodes the npm `snowden` package's mesh (base64 Float32 positions + Uint32 cells in hi.js, MIT)
// into a Wavefront OBJ. Called by tools/fetch_content.sh: node snowden_to_obj.js <package dir> <out.obj>
'use strict';
const fs = require('fs');
const path = require('path');
const [dir, out] = process.argv.slice(2);
if (!dir || !out) {
  console.error('usage: node snowden_to_obj.js <snowden package dir> <out.obj>');
  process.exit(2);
}
const text = fs.readFileSync(path.join(dir, 'hi.js'), 'utf8');
function field(name, Type) {
  const m = text.match(new RegExp('exports\\.' + name + '\\s*=\\s*require\\("\\./load"\\)\\(\\w+,\\s*"([^"]*)"'));
  if (!m) throw new Error('hi.js: no ' + name + ' field');
  const bytes = Buffer.from(m[1], 'base64');
  return new Type(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
}
const pos = field('positions', Float32Array);
const cells = field('cells', Uint32Array);
if (pos.length % 3 || cells.length % 3) throw new Error('hi.js: arrays are not triples');
const lines = ['# snowden head (npm snowden, MIT), ' + pos.length / 3 + ' vertices, ' + cells.length / 3 + ' triangles'];
for (let i = 0; i < pos.length; i += 3) lines.push('v ' + pos[i] + ' ' + pos[i + 1] + ' ' + pos[i + 2]);
for (let i = 0; i < cells.length; i += 3) {
  const a = cells[i], b = cells[i + 1], c = cells[i + 2];
  if (a * 3 >= pos.length || b * 3 >= pos.length || c * 3 >= pos.length) throw new Error('hi.js: index out of range');
  lines.push('f ' + (a + 1) + ' ' + (b + 1) + ' ' + (c + 1));
}
fs.writeFileSync(out, lines.join('\n') + '\n');
console.log('wrote ' + out + ': ' + pos.length / 3 + ' vertices, ' + cells.length / 3 + ' triangles');
