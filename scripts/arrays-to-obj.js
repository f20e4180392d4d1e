// Converts a mesh module of the form `exports.positions=[[x,y,z],...]` and
// `exports.cells=[[i,j,k],...]` (npm packages 'bunny', 'teapot') into an OBJ file, reading the
// arrays as JSON text (the module's code is not executed).
const fs = require('fs');
const [src, dst] = process.argv.slice(2);
const text = fs.readFileSync(src, 'utf8');
function array(name) {
  const m = text.match(new RegExp('exports\\.' + name + '\\s*=\\s*(\\[[\\s\\S]*?\\]\\])'));
  if (!m) throw new Error(src + ': no exports.' + name + ' array');
  return JSON.parse(m[1]);
}
const positions = array('positions');
const cells = array('cells');
const lines = [`# converted from ${src.split('/').slice(-2).join('/')}`];
for (const p of positions) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of cells) lines.push(`f ${c.map((i) => i + 1).join(' ')}`);
fs.writeFileSync(dst, lines.join('\n') + '\n');
