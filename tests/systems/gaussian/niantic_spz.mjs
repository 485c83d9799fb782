// Writes an SPZ with the official SPZ library (the WebAssembly build splat-transform bundles), told
// that its input is in the 3DGS PLY frame (RDF): the library converts to SPZ's RUB as Niantic's own
// tools do. Input: a JSON file {n, degree, positions, scales (log), rotations (wxyz), alphas (logit),
// colors (f_dc), sh (per splat, coefficient-major RGB)}. Usage: node niantic_spz.mjs DIST IN.json OUT.spz
// [VERSION] (the SPZ version written, default 3)
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
const [dist, input, output, versionArg] = process.argv.slice(2);
const version = versionArg ? Number(versionArg) : 3;
const index = readFileSync(join(dist, 'index.mjs'), 'utf8');
const file = index.match(/import\('\.\/(spz-[^']+\.js)'\)/)[1];
const { default: createModule } = await import(join(dist, file));
const spz = await createModule();
const j = JSON.parse(readFileSync(input, 'utf8'));
const rot = new Float32Array(j.n * 4);
for (let i = 0; i < j.n; ++i) {
    rot[i * 4] = j.rotations[i * 4 + 1];
    rot[i * 4 + 1] = j.rotations[i * 4 + 2];
    rot[i * 4 + 2] = j.rotations[i * 4 + 3];
    rot[i * 4 + 3] = j.rotations[i * 4];
}
const cloud = {
    numPoints: j.n, shDegree: j.degree, antialiased: false, extensions: [],
    positions: new Float32Array(j.positions), scales: new Float32Array(j.scales), rotations: rot,
    alphas: new Float32Array(j.alphas), colors: new Float32Array(j.colors), sh: new Float32Array(j.sh)
};
const bytes = spz.saveSpzToBuffer(cloud, { version, from: spz.CoordinateSystem.RDF, sh1Bits: 8, shRestBits: 8 });
writeFileSync(output, bytes);
