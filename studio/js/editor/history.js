// Undo and redo over every edit: each entry is a whole copy of the map as
// it was before the edit (maps are small: at most a few hundred KB of text),
// so any edit, a paint stroke or a generated map alike, undoes the same way.

const MAX_ENTRIES = 200;

export class History {
  constructor() {
    this.undoStack = [];  // [{model, label}]
    this.redoStack = [];
  }

  // Records `before` (a copy of the map before an edit named `label`).
  push(before, label) {
    this.undoStack.push({ model: before, label });
    if (this.undoStack.length > MAX_ENTRIES) this.undoStack.shift();
    this.redoStack = [];
  }

  canUndo() { return this.undoStack.length > 0; }
  canRedo() { return this.redoStack.length > 0; }

  // `current`: a copy of the map now; returns the map to show, or null.
  undo(current) {
    const entry = this.undoStack.pop();
    if (!entry) return null;
    this.redoStack.push({ model: current, label: entry.label });
    return entry;
  }

  redo(current) {
    const entry = this.redoStack.pop();
    if (!entry) return null;
    this.undoStack.push({ model: current, label: entry.label });
    return entry;
  }

  clear() {
    this.undoStack = [];
    this.redoStack = [];
  }
}
