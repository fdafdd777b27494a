// The buttons that talk to the daemon: Generate and Dress (GenerateMap),
// Open (ListMaps, OpenMap), Save (SaveMap: asks before replacing a file),
// Play (LoadMap.text). Every refusal is shown with the daemon's own message
// and leaves the editor's map as it was.

const $ = (id) => document.getElementById(id);

export class Actions {
  constructor(app) {
    this.app = app;
    this.saveNameAuto = true;  // the Save name follows the map's name until typed over
    $("generate").onclick = () => this.generate(false);
    $("dress").onclick = () => this.generate(true);
    $("open-map").onclick = () => this.open($("open-name").value);
    $("refresh-maps").onclick = () => this.listMaps();
    $("save-map").onclick = () => this.save();
    $("save-name").addEventListener("input", () => { this.saveNameAuto = $("save-name").value.trim() === ""; });
    $("play").onclick = () => this.play();
  }

  // The default Save name: studio/<map name>.
  render() {
    const name = `studio/${this.app.model.name || "untitled"}`;
    if (this.saveNameAuto && document.activeElement !== $("save-name")) $("save-name").value = name;
  }

  async listMaps() {
    try {
      const answer = await this.app.configure({ list_maps: {} });
      const select = $("open-name"), current = select.value;
      select.replaceChildren(...(answer.maps || []).map((name) => Object.assign(document.createElement("option"),
        { value: name, textContent: name })));
      if ((answer.maps || []).includes(current)) select.value = current;
      return answer.maps || [];
    } catch (error) {
      this.app.reportError(error, "ListMaps");
      return [];
    }
  }

  generationRequest(dress) {
    const request = { seed: Math.max(0, Math.round(Number($("gen-seed").value) || 0)) };
    const trees = $("gen-trees").value.trim();
    if (trees !== "") request.roadside_trees = Number(trees);
    if (dress) {
      request.layout_text = this.app.text();
    } else {
      request.width = Math.max(0, Math.round(Number($("gen-width").value) || 0));
      request.height = Math.max(0, Math.round(Number($("gen-height").value) || 0));
      request.tile_size = Number($("gen-tile-size").value) || 0;
      request.surroundings = $("gen-surroundings").value;
    }
    return request;
  }

  // GenerateMap (dress: keeps this map's roads and routes, new objects);
  // the answer replaces the editor's map as one undoable edit.
  async generate(dress) {
    const what = dress ? "Dress" : "Generate";
    try {
      const answer = await this.app.configure({ generate_map: this.generationRequest(dress) });
      if (this.app.loadText(answer.map_text || "", dress ? "dress" : "generate")) {
        this.app.note(dress ? "dressed: new objects around the same roads" : "generated a new map");
      }
    } catch (error) {
      this.app.reportError(error, what);
    }
  }

  async open(name) {
    if (!name) { this.app.note("no map to open: the maps folder lists none", true); return false; }
    try {
      const answer = await this.app.configure({ open_map: { name } });
      if (!this.app.loadText(answer.map_text || "", `open ${name}`)) return false;
      this.app.openedName = name;
      this.app.note(`opened ${name}`);
      return true;
    } catch (error) {
      this.app.reportError(error, "Open");
      return false;
    }
  }

  async save() {
    const name = $("save-name").value.trim(), text = this.app.text();
    const request = { save_map: { name, text, overwrite: false } };
    try {
      try {
        await this.app.configure(request);
      } catch (error) {
        if (error.code !== "ERROR_CODE_ALREADY_EXISTS") throw error;
        if (!window.confirm(`${error.message}\n\nReplace ${name}.map?`)) {
          this.app.note(`not saved: ${name}.map already exists`, true);
          return false;
        }
        request.save_map.overwrite = true;
        await this.app.configure(request);
      }
    } catch (error) {
      this.app.reportError(error, "Save");
      return false;
    }
    this.app.saved = { name, text };
    this.app.note(`saved ${name}.map (${text.length} bytes)`);
    await this.listMaps();
    return true;
  }

  // LoadMap.text: the daemon plays this map (its first closed route's car).
  async play() {
    this.app.preview.stopView();  // LoadMap removes the preview camera
    try {
      await this.app.configure({ load_map: { text: this.app.text() } });
    } catch (error) {
      this.app.reportError(error, "Play");
      return false;
    }
    this.app.note(`playing ${this.app.model.name} in the daemon`);
    return true;
  }
}
