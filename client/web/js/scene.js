// The scene a browser shades (GET /v1/scene, server/web_scene.h): one zstd frame holding
// "PICWEB1\0", the JSON header's length (uint32 LE), the JSON, zero padding to 16 bytes and
// the binary sections the JSON lists (the G-buffer records of shaders/shared/gbuffer.h, the
// texels and the caches' index maps), little-endian.
import { decompress } from 'fzstd';

const kMagic = 'PICWEB1\0';

/// Parses the decompressed or compressed blob; throws naming what is wrong.
export function parseScene(compressed) {
  const bytes = decompress(compressed);
  const magic = String.fromCharCode(...bytes.subarray(0, 8));
  if (magic !== kMagic) throw new Error(`scene: not a pic web scene (starts "${magic}")`);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLength = view.getUint32(8, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(12, 12 + jsonLength)));
  if (json.format !== 1) throw new Error(`scene: format ${json.format}, this page reads format 1`);
  const start = Math.ceil((12 + jsonLength) / 16) * 16;
  const sections = {};
  for (const s of json.sections) {
    const at = start + s.offset;
    if (at + s.bytes > bytes.byteLength)
      throw new Error(`scene: section ${s.name} (${s.bytes} bytes at ${at}) runs past the ${bytes.byteLength} bytes`);
    // A copy aligned for typed arrays: sections start at multiples of 16 already.
    sections[s.name] = { ...s, data: bytes.subarray(at, at + s.bytes) };
  }
  for (const name of ['vertices', 'triangles', 'materials', 'textures', 'levels', 'texels',
                      'grid_caches', 'lightmap_caches'])
    if (!sections[name]) throw new Error(`scene: section ${name} is missing`);
  const u32 = (name) => {
    const d = sections[name].data;
    return new Uint32Array(d.buffer, d.byteOffset, d.byteLength / 4);
  };
  const f32 = (name) => {
    const d = sections[name].data;
    return new Float32Array(d.buffer, d.byteOffset, d.byteLength / 4);
  };
  return {
    ...json,
    bytes: compressed.byteLength,
    vertices: f32('vertices'),        // 16 floats per corner (GbufferVertex)
    triangles: u32('triangles'),      // 12 words per triangle (GbufferTriangle)
    materialRecords: u32('materials'),  // 12 words per material (GbufferMaterial)
    textures: u32('textures'),        // 4 words per texture (GbufferTexture)
    levels: u32('levels'),            // 4 words per mip level (GbufferTextureLevel)
    texels: f32('texels'),            // RGBA per texel
    gridCaches: u32('grid_caches'),
    lightmapCaches: u32('lightmap_caches'),
  };
}
