// The colour maps of render/src/color_map.cpp (matplotlib's, sampled at i/16), so the viewer's
// curvature colours read like the project's rendered figures.
const COOLWARM = [[0.2298, 0.2987, 0.7537], [0.3042, 0.4069, 0.8453], [0.3837, 0.5102, 0.9178],
  [0.4677, 0.6056, 0.9685], [0.5543, 0.6901, 0.9955], [0.6408, 0.7608, 0.9978], [0.7240, 0.8149, 0.9757],
  [0.8006, 0.8504, 0.9300], [0.8674, 0.8644, 0.8626], [0.9256, 0.8255, 0.7711], [0.9595, 0.7670, 0.6741],
  [0.9697, 0.6905, 0.5751], [0.9567, 0.5980, 0.4773], [0.9214, 0.4914, 0.3834], [0.8654, 0.3711, 0.2958],
  [0.7906, 0.2314, 0.2162], [0.7057, 0.0156, 0.1502]];
const VIRIDIS = [[0.2670, 0.0049, 0.3294], [0.2823, 0.0950, 0.4173], [0.2788, 0.1755, 0.4834],
  [0.2590, 0.2515, 0.5247], [0.2297, 0.3224, 0.5457], [0.1994, 0.3876, 0.5546], [0.1727, 0.4488, 0.5579],
  [0.1490, 0.5081, 0.5573], [0.1276, 0.5669, 0.5506], [0.1206, 0.6258, 0.5335], [0.1579, 0.6838, 0.5017],
  [0.2461, 0.7389, 0.4520], [0.3692, 0.7889, 0.3829], [0.5160, 0.8312, 0.2943], [0.6785, 0.8637, 0.1895],
  [0.8456, 0.8873, 0.0997], [0.9932, 0.9062, 0.1439]];

// Sign convention of cdp::curvature_at: the gradient points outward, so a convex cap has k1, k2 > 0,
// positive mean curvature and shape index -1.
export const SCALARS = {
  shape_index: {
    table: COOLWARM, log: false,
    value: (k1, k2) => -(2 / Math.PI) * Math.atan((k1 + k2) / (k1 - k2)),
    ends: ["−1 convex cap", "0 saddle", "+1 concave cup"],
  },
  mean: {
    table: COOLWARM, log: false,
    value: (k1, k2) => 0.5 * (k1 + k2),
    ends: (lo, hi) => [fmt(lo) + " concave", "0", fmt(hi) + " convex"],
  },
  mac: {
    table: VIRIDIS, log: true,
    value: (k1, k2) => Math.max(Math.abs(k1), Math.abs(k2)),
    ends: (lo, hi) => [fmt(lo), "max |k| (log scale)", fmt(hi)],
  },
};

function fmt(v) {
  return Math.abs(v) >= 100 || (Math.abs(v) < 0.01 && v !== 0) ? v.toExponential(1) : v.toPrecision(3);
}

// Grey for NaN (no gradient there), as the renderer does.
export function colorAt(table, t, out, o) {
  if (!Number.isFinite(t)) {
    out[o] = out[o + 1] = out[o + 2] = 0.5;
    return;
  }
  const x = Math.min(Math.max(t, 0), 1) * 16;
  const i = Math.min(15, Math.floor(x));
  const f = x - i;
  for (let k = 0; k < 3; k++) out[o + k] = (1 - f) * table[i][k] + f * table[i + 1][k];
}

// Per-vertex colours, in linear RGB (three.js treats vertex colours as linear).
export function vertexColors(name, range, k1, k2, toLinear) {
  const s = SCALARS[name];
  const n = k1.length;
  const out = new Float32Array(3 * n);
  let [a, b] = range;
  if (s.log) [a, b] = [Math.log10(a), Math.log10(b)];
  for (let i = 0; i < n; i++) {
    let v = s.value(k1[i], k2[i]);
    if (s.log) v = v > 0 ? Math.log10(v) : -Infinity;
    colorAt(s.table, b > a ? (v - a) / (b - a) : 0.5, out, 3 * i);
  }
  for (let i = 0; i < out.length; i++) out[i] = toLinear(out[i]);
  return out;
}

export function legendLabels(name, range) {
  const e = SCALARS[name].ends;
  return typeof e === "function" ? e(range[0], range[1]) : e;
}

export function tableOf(name) {
  return SCALARS[name].table;
}
