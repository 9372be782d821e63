// Vectors as arrays [x, y, z] (on the page, world metres): the arithmetic the camera, measuring,
// sections and the site's projector share, and the check of a vector read from JSON.
export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
export const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
export const norm = (a) => Math.sqrt(dot(a, a));
export const unit = (a) => mul(a, 1 / norm(a));

export const finite = (v) => typeof v === 'number' && Number.isFinite(v);
export const vec3 = (v) => Array.isArray(v) && v.length === 3 && v.every(finite);
