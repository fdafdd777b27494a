// Building page elements from strings that came over the network (entity,
// camera, route and map names, error messages): always as text, never as
// markup, so a name like `<img src=x onerror=...>` shows literally and runs
// nothing (the daemon's Content-Security-Policy forbids inline script too).

// An <option> showing `text` with value `value` (text when omitted).
export function option(text, value = text) {
  return Object.assign(document.createElement("option"), { value: String(value), textContent: String(text) });
}

// Replaces `select`'s options with `options` (from option()); keeps the
// choice when it is still offered, else selects the first.
export function setOptions(select, options, keepChoice = true) {
  const current = select.value;
  select.replaceChildren(...options);
  if (keepChoice && current && options.some((o) => o.value === current)) select.value = current;
  if (select.selectedIndex < 0 && options.length) select.selectedIndex = 0;
}
