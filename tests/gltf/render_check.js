// render_check.js: where the bodies of a run show in f3d's picture of its
// glTF file (tests/gltf/check.sh).
//
//   node render_check.js f3d-args        the camera options for f3d
//   node render_check.js check CSV PNG   check the picture against the CSV
//
// The camera is fixed here, so that a body's pixel follows from its
// position: a pinhole at world (0, -8, 0.5) looking along +y with z up and
// a vertical view angle of 30 degrees, 400 x 300 pixels, on black. The
// glTF root turns world z up into glTF's y up, (x, y, z) -> (x, z, -y),
// so f3d gets the camera in those coordinates.
//
// The check, at the first frame (f3d shows an animation's start): the
// pixel at each body's projected centre of mass is lit (some channel above
// 40 of 255, where the background is 0), and the pixels half way between
// neighbouring bodies and at the picture's top corners are background
// (every channel below 10). Why the bounds hold: the scene's bodies
// (tests/gltf/scene.lua) are 0.2 to 0.3 m in radius at 8 m, 14 to 21
// pixels across their centre, so a projection off by a pixel or two, or
// floats' 1e-7 m, still lands inside; the gaps between them are 1 m wide
// (at least 0.3 m, 20 pixels, from any body at the midpoint), and the
// bodies stand 1 m above the camera against the empty sky, so a body drawn
// where the CSV does not put it, or not turned z up, fails one of them.
// Lit faces face the camera's headlight: the bodies' orange reads about
// (150, 100, 60), far above 40.
'use strict';
const fs = require('fs');
const zlib = require('zlib');

const W = 400, H = 300, VIEW = 30;
const EYE = [0, -8, 0.5], AT = [0, 0, 0.5];
const gl = (p) => [p[0], p[2], -p[1]];

if (process.argv[2] === 'f3d-args') {
  // --dry-run: no configuration file, so a user's settings change nothing
  console.log(['--dry-run', `--resolution=${W},${H}`, '--bg-color=0,0,0', '--up=+Y', `--camera-view-angle=${VIEW}`,
               `--camera-position=${gl(EYE)}`, `--camera-focal-point=${gl(AT)}`, '--camera-view-up=0,1,0'].join(' '));
  process.exit(0);
}
if (process.argv[2] !== 'check' || process.argv.length !== 5) {
  console.error('usage: node render_check.js f3d-args | check CSV PNG');
  process.exit(2);
}

// A PNG's pixels: 8-bit RGB or RGBA, not interlaced (what f3d writes).
function readPng(file) {
  const b = fs.readFileSync(file);
  if (b.toString('latin1', 1, 4) !== 'PNG') throw new Error(`${file} is not a PNG`);
  let pos = 8, w = 0, h = 0, depth = 0, type = 0, interlace = 0;
  const idat = [];
  while (pos < b.length) {
    const len = b.readUInt32BE(pos), kind = b.toString('latin1', pos + 4, pos + 8);
    const data = b.subarray(pos + 8, pos + 8 + len);
    if (kind === 'IHDR') {
      w = data.readUInt32BE(0); h = data.readUInt32BE(4);
      depth = data[8]; type = data[9]; interlace = data[12];
    } else if (kind === 'IDAT') {
      idat.push(data);
    }
    pos += 12 + len;
  }
  if (depth !== 8 || (type !== 2 && type !== 6) || interlace)
    throw new Error(`${file}: PNG depth ${depth}, colour type ${type}, interlace ${interlace} not read here`);
  const bpp = type === 6 ? 4 : 3, stride = w * bpp;
  const raw = zlib.inflateSync(Buffer.concat(idat)), px = Buffer.alloc(h * stride);
  for (let y = 0; y < h; ++y) {
    const f = raw[y * (stride + 1)], src = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let x = 0; x < stride; ++x) {
      const a = x >= bpp ? px[y * stride + x - bpp] : 0, up = y ? px[(y - 1) * stride + x] : 0;
      const c = x >= bpp && y ? px[(y - 1) * stride + x - bpp] : 0;
      let v = src[x];
      if (f === 1) v += a;
      else if (f === 2) v += up;
      else if (f === 3) v += (a + up) >> 1;
      else if (f === 4) {
        const p = a + up - c, pa = Math.abs(p - a), pb = Math.abs(p - up), pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? up : c;
      }
      px[y * stride + x] = v & 255;
    }
  }
  return { w, h, at: (x, y) => Array.from(px.subarray(y * stride + x * bpp, y * stride + x * bpp + 3)) };
}

// The pixel (column, row) where world point p projects.
function project(p) {
  const t = Math.tan(VIEW * Math.PI / 360), depth = p[1] - EYE[1];
  const x = (p[0] - EYE[0]) / depth / t / (W / H), y = (p[2] - EYE[2]) / depth / t;
  return [Math.round((x + 1) / 2 * W - 0.5), Math.round((1 - y) / 2 * H - 0.5)];
}

const [csvFile, pngFile] = process.argv.slice(3);
const rows = fs.readFileSync(csvFile, 'utf8').trim().split('\n').slice(1).map((l) => l.split(','));
const bodies = rows.filter((r) => r[1] === 'body' && Number(r[0]) === 0).map((r) => r.slice(3, 6).map(Number));
const img = readPng(pngFile);
let failed = 0;
const check = (what, xy, lit) => {
  const c = img.at(xy[0], xy[1]), ok = lit ? Math.max(...c) > 40 : Math.max(...c) < 10;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what} at pixel (${xy}): rgb (${c}), expected ${lit ? 'lit' : 'background'}`);
  failed += !ok;
};
if (img.w !== W || img.h !== H) throw new Error(`${pngFile} is ${img.w} x ${img.h}, not ${W} x ${H}`);
if (bodies.length < 2) throw new Error(`${csvFile} has ${bodies.length} bodies at t = 0; the check needs two or more`);
bodies.sort((a, b) => a[0] - b[0]);
bodies.forEach((p, i) => {
  check(`body ${i + 1} (${p})`, project(p), true);
  if (i) check(`half way to body ${i}`, project(p.map((v, k) => (v + bodies[i - 1][k]) / 2)), false);
});
check('top left corner', [2, 2], false);
check('top right corner', [W - 3, 2], false);
if (failed) {
  console.log(`render_check.js: ${failed} pixel(s) wrong`);
  process.exit(1);
}
