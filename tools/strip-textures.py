#!/usr/bin/env python3
"""A GLB without its textures (materials keep their factors), for measuring how meshes whose UVs no
texture reads are simplified (docs/lod.md, "UVs no texture reads"). The image data stays in the
binary chunk, unreferenced.

usage: tools/strip-textures.py IN.glb OUT.glb"""
import json, struct, sys
src, dst = sys.argv[1], sys.argv[2]
b = open(src, 'rb').read()
magic, ver, total = struct.unpack_from('<III', b, 0)
jlen, jtype = struct.unpack_from('<II', b, 12)
j = json.loads(b[20:20 + jlen])
rest = b[20 + jlen:]
for m in j.get('materials', []):
    pbr = m.get('pbrMetallicRoughness', {})
    pbr.pop('baseColorTexture', None)
    m.pop('normalTexture', None); m.pop('emissiveTexture', None); m.pop('occlusionTexture', None)
j.pop('textures', None); j.pop('images', None); j.pop('samplers', None)
js = json.dumps(j, separators=(',', ':')).encode()
js += b' ' * ((4 - len(js) % 4) % 4)
out = struct.pack('<III', magic, ver, 12 + 8 + len(js) + len(rest)) + struct.pack('<II', len(js), jtype) + js + rest
open(dst, 'wb').write(out)
