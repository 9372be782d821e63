// The page's shared state: the backend that renders (controls.js describes it), the scene it
// loaded (view/source.h's JSON), the camera (view.json's fields), the settings (the protocol's)
// and whether camera or settings changed since the backend last had them. Other modules read
// these bindings (they follow every set below) and change the objects' fields in place.
import { $ } from './dom.js';

export const canvas = $('view');
export let backend = null;
export let scene = null;
export let camera = null;
export let settings = null;
export let dirty = false;

export function setBackend(b) { backend = b; }
export function setScene(s) { scene = s; }
export function setCamera(c) { camera = c; }
export function setSettings(s) { settings = s; }
export function changed() { dirty = true; }
export function sent() { dirty = false; }
export function clone(c) { return JSON.parse(JSON.stringify(c)); }
