// Read a DDS file with parse-dds or a KTX2 file with ktx-parse, envconv's independent readers.
// Usage: node read_container.mjs FILE OUT.bin
// Prints the reader's header fields as JSON and writes the bytes of every image the reader
// located, in the reader's order, to OUT.bin (DDS: face by face, each level in turn;
// KTX2: level by level, level 0 first, as ktx-parse's levels[] array).
import { readFileSync, writeFileSync } from 'node:fs';
import parseDDS from 'parse-dds';
import { read } from 'ktx-parse';

const [file, out] = process.argv.slice(2);
const bytes = readFileSync(file);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
let info;
let chunks;
if (file.toLowerCase().endsWith('.dds')) {
  const dds = parseDDS(buffer);
  chunks = dds.images.map((im) => new Uint8Array(buffer, im.offset, im.length));
  info = {
    reader: 'parse-dds', format: dds.format, cubemap: dds.cubemap, flags: dds.flags,
    shape: dds.shape, images: dds.images,
  };
} else {
  const ktx = read(new Uint8Array(buffer));
  chunks = ktx.levels.map((level) => level.levelData);
  info = {
    reader: 'ktx-parse', vkFormat: ktx.vkFormat, typeSize: ktx.typeSize,
    pixelWidth: ktx.pixelWidth, pixelHeight: ktx.pixelHeight, pixelDepth: ktx.pixelDepth,
    layerCount: ktx.layerCount, faceCount: ktx.faceCount, levelCount: ktx.levels.length,
    supercompressionScheme: ktx.supercompressionScheme,
    levels: ktx.levels.map((l) => ({ byteLength: l.levelData.byteLength,
      uncompressedByteLength: Number(l.uncompressedByteLength) })),
    dfd: ktx.dataFormatDescriptor[0],
    keyValue: Object.fromEntries(Object.entries(ktx.keyValue).map(([k, v]) =>
      [k, typeof v === 'string' ? v : Buffer.from(v).toString('utf8')])),
  };
}
writeFileSync(out, Buffer.concat(chunks.map((c) => Buffer.from(c.buffer, c.byteOffset, c.byteLength))));
process.stdout.write(JSON.stringify(info));
