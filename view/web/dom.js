// The page's small DOM helpers: an element by its id, a file offered for download, a link to a
// file made in the page.
export const $ = (id) => document.getElementById(id);

export function download(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

export function blobLink(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.textContent = name;
  return a;
}
