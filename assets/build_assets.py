#!/usr/bin/python3
"""Builds the people bundle the renderer draws walkers with (docs/assets.md).

Reads textured, posed people (OBJ + MTL + JPEG textures, centimetres, y up)
straight out of Debian's sweethome3d-furniture archives (zip files, .sh3f),
and writes a lean bundle the daemon compiles in:

- each person in metres, z up, facing +x, feet on z = 0, centred over the
  origin, scaled to PERSON_HEIGHT_M (the walker's 3D box, traffic_meshes.h);
- simplified by vertex clustering on a uniform grid to about TARGET_TRIANGLES
  triangles (the grid's cell is searched for, so the count is a fixed
  function of the source mesh: the same package gives the same bytes);
- the textures baked into vertex colours (each triangle's texture sampled at
  its corners and centre, averaged per clustered vertex by triangle area),
  so the renderer needs no texture and colour stays one pass with the
  ground truth.

Each person comes at two levels of detail: TARGET_TRIANGLES, and
FAR_TRIANGLES for when it is small on screen (the renderer picks per camera).

Outputs: a C++ source holding the bundle as bytes (--cpp), the bundle as a
file (--bin, optional) and the attribution list (--attribution, Markdown).
Bundle layout, little-endian: b"S4CVPPL2", u32 person count, u32 level
count (2), then per person per level (full first) a mesh: u32 vertex count,
u32 index count, vertex count x 9 float32 (position xyz, normal xyz, linear
RGB colour), index count x u32 (counter-clockwise triangles seen from
outside). server/render/people_bundle.cpp reads it.

With --empty (the package is not installed) it writes a bundle of no
models; the renderer then draws its procedural walkers and says so.

  /usr/bin/python3 assets/build_assets.py --cpp OUT.cpp --attribution OUT.md [--bin OUT.bin]
      [--preview DIR] [--empty]
"""

import argparse
import io
import os
import re
import struct
import sys
import zipfile

import numpy as np
from PIL import Image

FURNITURE_DIR = "/usr/share/sweethome3d/furniture"
PERSON_HEIGHT_M = 1.74  # 1 cm under the walker box (kPedestrianBox), room for the sway
TARGET_TRIANGLES = 2000
FAR_TRIANGLES = 700
MAGIC = b"S4CVPPL2"

# The people used, in bundle order: (archive, catalogue id). Adults standing
# upright in different clothes, chosen by looking at each (--preview).
# Sitting, lying and children's models are left out (a walker's box is an
# adult's), and so are those wider than the walker's box (kPedestrianBox,
# 0.66 m shoulder to shoulder, walker_looks_test.cpp): male02 (0.77 m,
# standing astride), holdingFemale02 (0.71 m, elbows out).
PEOPLE = [
    ("Reallusion.sh3f", "Reallusion#female01"),
    ("Reallusion.sh3f", "Reallusion#male01"),
    ("Reallusion.sh3f", "Reallusion#female02"),
    ("Reallusion.sh3f", "Reallusion#holdingMale01"),
    ("Reallusion.sh3f", "Reallusion#female03"),
    ("Reallusion.sh3f", "Reallusion#male03"),
    ("Reallusion.sh3f", "Reallusion#holdingFemale01"),
]


def read_catalogue(archive):
    """The archive's catalogue: {id: {key: value}} and the catalogue's own fields."""
    text = archive.read("PluginFurnitureCatalog.properties").decode("latin-1")
    entries, header = {}, {}
    by_index = {}
    for line in text.splitlines():
        if not line or line.startswith("#") or "=" not in line:
            continue
        key, value = line.split("=", 1)
        match = re.fullmatch(r"(\w+)#(\d+)", key)
        if match:
            by_index.setdefault(int(match.group(2)), {})[match.group(1)] = value
        else:
            header[key] = value
    for fields in by_index.values():
        entries[fields["id"]] = fields
    return entries, header


def parse_mtl(text):
    """{material: (diffuse rgb, texture file or None)}."""
    materials, name = {}, None
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "newmtl":
            name = " ".join(parts[1:])
            materials[name] = [np.ones(3), None]
        elif name is not None and parts[0] == "Kd":
            materials[name][0] = np.array([float(x) for x in parts[1:4]])
        elif name is not None and parts[0] == "map_Kd":
            materials[name][1] = parts[-1]
    return materials


def parse_obj(text):
    """Positions (n, 3), uvs (m, 2), triangles as (position index, uv index or -1) x 3 and their material."""
    positions, uvs, corners, materials = [], [], [], []
    material = None
    for line in text.splitlines():
        if line.startswith("v "):
            positions.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("vt "):
            uvs.append([float(x) for x in line.split()[1:3]])
        elif line.startswith("usemtl "):
            material = line[7:].strip()
        elif line.startswith("f "):
            face = []
            for token in line.split()[1:]:
                fields = token.split("/")
                v = int(fields[0])
                t = int(fields[1]) if len(fields) > 1 and fields[1] else 0
                v = v - 1 if v > 0 else len(positions) + v
                t = (t - 1 if t > 0 else len(uvs) + t) if t else -1
                face.append((v, t))
            for i in range(1, len(face) - 1):  # a fan of triangles
                corners.append((face[0], face[i], face[i + 1]))
                materials.append(material)
    return np.array(positions), np.array(uvs) if uvs else np.zeros((0, 2)), corners, materials


def srgb_to_linear(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def triangle_colours(archive, folder, corners, tri_materials, uvs, materials):
    """Linear RGB per triangle: its texture at its three corners and centre, times the diffuse colour."""
    textures = {}
    colours = np.zeros((len(corners), 3))
    for index, ((a, b, c), name) in enumerate(zip(corners, tri_materials)):
        kd, texture = materials.get(name, (np.ones(3), None))
        if texture is None or min(a[1], b[1], c[1]) < 0:
            colours[index] = kd
            continue
        if texture not in textures:
            image = Image.open(io.BytesIO(archive.read(folder + texture))).convert("RGB")
            textures[texture] = np.asarray(image, dtype=np.float64) / 255.0
        pixels = textures[texture]
        h, w = pixels.shape[:2]
        st = uvs[[a[1], b[1], c[1]]]
        st = np.vstack([st, st.mean(axis=0)])
        x = (np.mod(st[:, 0], 1.0) * (w - 1)).round().astype(int)
        y = ((1.0 - np.mod(st[:, 1], 1.0)) * (h - 1)).round().astype(int)
        colours[index] = srgb_to_linear(pixels[y, x]).mean(axis=0) * kd
    return colours


def stand(p):
    """Feet on z = 0, PERSON_HEIGHT_M tall, centred over the origin."""
    p = p - [0.0, 0.0, p[:, 2].min()]
    p = p * (PERSON_HEIGHT_M / p[:, 2].max())
    centre = (p[:, :2].min(axis=0) + p[:, :2].max(axis=0)) / 2.0
    p[:, :2] -= centre
    return p


def to_metres_z_up(positions):
    """OBJ's y-up centimetres, facing +z, to z-up metres facing +x, feet on 0, scaled to PERSON_HEIGHT_M."""
    # (x, y, z) y-up facing +z  ->  forward = z, left = x, up = y.
    return stand(np.stack([positions[:, 2], positions[:, 0], positions[:, 1]], axis=1))


def cluster(positions, triangles, cell):
    """Vertex clustering: vertices in one grid cell become one; triangles that collapse go."""
    keys = np.floor(positions / cell).astype(np.int64)
    _, cluster_of, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    cluster_of = cluster_of.reshape(-1)
    tris = cluster_of[triangles]
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[keep]
    # One copy of each triangle (same corners in the same turning order).
    rolled = np.array([np.roll(t, -int(np.argmin(t))) for t in tris]) if len(tris) else tris
    _, first = np.unique(rolled, axis=0, return_index=True)
    kept = np.flatnonzero(keep)[np.sort(first)]
    return cluster_of, counts, rolled[np.sort(first)], kept


def simplify(positions, triangles, colours, target):
    """About `target` triangles: the largest grid cell (binary search) whose clustering keeps at least target."""
    low, high = 0.001, 0.2
    for _ in range(30):
        mid = (low + high) / 2.0
        if len(cluster(positions, triangles, mid)[2]) >= target:
            low = mid
        else:
            high = mid
    cluster_of, counts, tris, kept = cluster(positions, triangles, low)
    n = counts.size
    sums = np.zeros((n, 3))
    np.add.at(sums, cluster_of, positions)
    new_positions = sums / counts[:, None]
    # Colours by area of the source triangles touching each cluster.
    corners = positions[triangles]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    weight = np.zeros(n)
    colour_sums = np.zeros((n, 3))
    for k in range(3):
        np.add.at(weight, cluster_of[triangles[:, k]], areas)
        np.add.at(colour_sums, cluster_of[triangles[:, k]], colours * areas[:, None])
    new_colours = colour_sums / np.maximum(weight, 1e-12)[:, None]
    # Only clusters some kept triangle uses.
    used = np.unique(tris)
    remap = -np.ones(n, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return new_positions[used], new_colours[used], remap[tris]


def vertex_normals(positions, triangles):
    corners = positions[triangles]
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])  # area-weighted
    normals = np.zeros_like(positions)
    for k in range(3):
        np.add.at(normals, triangles[:, k], face)
    # Where faces cancel (a thin two-sided part clustered onto itself), the largest face's normal.
    largest, largest_area = np.zeros_like(positions), np.zeros(len(positions))
    area = np.linalg.norm(face, axis=1)
    for t in np.argsort(area):  # ascending: the largest face is written last
        largest[triangles[t]] = face[t]
        largest_area[triangles[t]] = area[t]
    length = np.linalg.norm(normals, axis=1)
    normals = np.where((length > 1e-3 * np.maximum(largest_area, 1e-30))[:, None], normals, largest)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0)


def convert(archive, entry):
    model_path = entry["model"].lstrip("/")
    folder = model_path.rsplit("/", 1)[0] + "/"
    obj = parse_obj(archive.read(model_path).decode("latin-1"))
    positions, uvs, corners, tri_materials = obj
    mtl_name = re.search(r"^mtllib\s+(.+)$", archive.read(model_path).decode("latin-1"), re.M).group(1).strip()
    materials = parse_mtl(archive.read(folder + mtl_name).decode("latin-1"))
    colours = triangle_colours(archive, folder, corners, tri_materials, uvs, materials)
    triangles = np.array([[a[0], b[0], c[0]] for a, b, c in corners], dtype=np.int64)
    source = to_metres_z_up(positions)
    levels = []
    for target in (TARGET_TRIANGLES, FAR_TRIANGLES):
        p, c, tris = simplify(source, triangles, colours, target)
        p = stand(p)  # clustering moved the soles up and the crown down
        levels.append({"positions": p, "normals": vertex_normals(p, tris), "colours": np.clip(c, 0.0, 1.0),
                       "indices": tris})
    return dict(levels[0], far=levels[1], source_triangles=len(triangles))


def pack(models):
    out = bytearray(MAGIC + struct.pack("<II", len(models), 2))
    for m in [level for model in models for level in (model, model["far"])]:
        vertices = np.hstack([m["positions"], m["normals"], m["colours"]]).astype("<f4")
        out += struct.pack("<II", len(vertices), m["indices"].size)
        out += vertices.tobytes()
        out += m["indices"].astype("<u4").tobytes()
    return bytes(out)


def write_cpp(path, bundle):
    lines = ["// Generated by assets/build_assets.py from sweethome3d-furniture: do not edit.",
             "#include <cstddef>", "", "namespace sim4cv::render {",
             "extern const unsigned char kPeopleBundle[];", "extern const std::size_t kPeopleBundleSize;",
             "alignas(16) const unsigned char kPeopleBundle[] = {"]
    for start in range(0, len(bundle), 24):
        lines.append("  " + ",".join(str(b) for b in bundle[start:start + 24]) + ",")
    lines += ["  0};", "const std::size_t kPeopleBundleSize = %d;" % len(bundle), "}  // namespace sim4cv::render", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


def write_preview(path, m):
    """Front (from +x) and side views, flat colours, painter's order: for choosing models by eye."""
    from PIL import ImageDraw
    size = 400
    image = Image.new("RGB", (2 * size, size), (200, 200, 200))
    draw = ImageDraw.Draw(image)
    gamma = np.clip(m["colours"], 0, 1) ** (1 / 2.2)
    for view, (axis_h, depth_axis, sign) in enumerate([(1, 0, -1.0), (0, 1, 1.0)]):
        corners = m["positions"][m["indices"]]
        order = np.argsort(sign * -corners[:, :, depth_axis].mean(axis=1))
        for t in order:
            pts = [(view * size + size / 2 + sign * v[axis_h] * size / 2.0, size - 10 - v[2] * size / 2.0)
                   for v in corners[t]]
            col = tuple(int(255 * x) for x in gamma[m["indices"][t]].mean(axis=0))
            draw.polygon(pts, fill=col)
    image.save(path)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cpp", required=True)
    parser.add_argument("--attribution", required=True)
    parser.add_argument("--bin")
    parser.add_argument("--preview")
    parser.add_argument("--empty", action="store_true")
    args = parser.parse_args(argv)
    models, rows = [], []
    if not args.empty:
        archives = {}
        for archive_name, model_id in PEOPLE:
            if archive_name not in archives:
                archive = zipfile.ZipFile(os.path.join(FURNITURE_DIR, archive_name))
                archives[archive_name] = (archive, *read_catalogue(archive))
            archive, entries, header = archives[archive_name]
            entry = entries[model_id]
            model = convert(archive, entry)
            models.append(model)
            rows.append((model_id, entry.get("name", ""), entry.get("creator", ""), header.get("license", ""),
                         archive_name, entry["model"], model["source_triangles"], len(model["indices"]),
                         len(model["far"]["indices"])))
            if args.preview:
                os.makedirs(args.preview, exist_ok=True)
                write_preview(os.path.join(args.preview, model_id.split("#")[1] + ".png"), model)
    bundle = pack(models)
    write_cpp(args.cpp, bundle)
    if args.bin:
        with open(args.bin, "wb") as f:
            f.write(bundle)
    with open(args.attribution, "w") as f:
        f.write("# Third-party art in sim4cvd\n\n")
        if not rows:
            f.write("None: built without sweethome3d-furniture; walkers are procedural.\n")
        else:
            f.write("Walkers are drawn with these models from Debian's `sweethome3d-furniture` package\n"
                    "(%s/), simplified and with their textures baked into vertex colours by\n"
                    "assets/build_assets.py. Each model's licence as its archive's catalogue states it\n"
                    "(the package's copyright file: /usr/share/doc/sweethome3d-furniture/copyright).\n\n"
                    % FURNITURE_DIR)
            f.write("| # | model | title | author | licence | source | triangles (source -> full, far) |\n")
            f.write("|---|---|---|---|---|---|---|\n")
            for i, (model_id, name, creator, licence, archive_name, path, src, dst, far) in enumerate(rows):
                f.write("| %d | %s | %s | %s | %s | %s:%s | %d -> %d, %d |\n"
                        % (i, model_id, name, creator, licence.replace("\ufffd", "(c)"), archive_name, path, src, dst,
                           far))
    print("people bundle: %d people, %d bytes, %s triangles" % (
        len(models), len(bundle), [(len(m["indices"]), len(m["far"]["indices"])) for m in models]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
