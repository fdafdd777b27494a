// The editor's keys: Ctrl+Z undo, Ctrl+Y or Ctrl+Shift+Z redo, r / R turn
// (clockwise / counter-clockwise), Delete removes the selection, Backspace
// the selected route's last tile, Escape back to the select tool. Keys
// typed into a field stay the field's.

function typing(target) {
  return target instanceof HTMLElement && (target.isContentEditable || ["INPUT", "SELECT", "TEXTAREA"].includes(target.tagName));
}

export function bindKeys(app) {
  window.addEventListener("keydown", (e) => {
    if (typing(e.target)) return;
    const key = e.key.toLowerCase(), ctrl = e.ctrlKey || e.metaKey;
    let handled = true;
    if (ctrl && key === "z" && !e.shiftKey) app.undo();
    else if (ctrl && (key === "y" || (key === "z" && e.shiftKey))) app.redo();
    else if (ctrl || e.altKey) handled = false;
    else if (key === "r") app.rotate(!e.shiftKey);
    else if (e.key === "Delete") app.deleteSelection();
    else if (e.key === "Backspace") handled = app.routes.removeLastTile() || app.routeIndex !== null;
    else if (e.key === "Escape") { app.pickTool(app.palette.item("select")); app.select({}); }
    else handled = false;
    if (handled) e.preventDefault();
  });
}
