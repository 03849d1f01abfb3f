#!/usr/bin/env python3
"""The bad-input corpus: malformed and extreme scene files, --set edits, CLI flags and VDB files,
each with its expected outcome, run through `candela-cli render` with a time and memory limit.

Outcomes:
  error   exit 2 (InputError) and a message "error: FILE: ... PATTERN" that names the scene file
  render  exit 0 and an image written
  render-warning  exit 0, an image written and a "warning: ... PATTERN" line (how it read the input)
  clean   either of the above (bit-flipped files: some flips leave a valid file)
  usage   the command line is refused (CLI11), exit != 0, PATTERN in the message
Anything else (a signal, exit 1 with an unnamed message, a timeout, the address-space limit, a
peak RSS above --peak-mb) fails.

Usage: corpus.py --cli CANDELA_CLI --hostile-vdb HOSTILE_VDB --scene SCENE.json --work DIR
                 [--filter SUBSTRING] [--timeout S] [--memory-gb G] [--list]
VDB files are made at run time: hostile_vdb writes the extreme ones, `candela-cli generate` a
valid one, which is then truncated and bit-flipped.
"""
import argparse
import base64
import json
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import time
import zlib

JUNK = ['null', '"text"', '[]', '{}', 'true', '1e309']


class Case:
    def __init__(self, name, expect, pattern='', sets=(), scene=None, flags=(), prepare=None):
        self.name, self.expect, self.pattern = name, expect, pattern
        self.sets, self.scene, self.flags, self.prepare = list(sets), scene, list(flags), prepare


def field_cases(path, ok=(), bad=(), junk=True, pattern=None):
    """Valid values must render; invalid ones must name the field."""
    pat = re.escape(pattern or path)
    out = [Case(f'set {path}={v}', 'render', '', [f'{path}={v}']) for v in ok]
    out += [Case(f'set {path}={v}', 'error', pat, [f'{path}={v}']) for v in bad]
    if junk:
        out += [Case(f'set {path}={v}', 'error', pat, [f'{path}={v}']) for v in JUNK]
    return out


def set_cases():
    vec_bad = ['[1e30,0,0]', '[0,-1e30,0]', '[1e7,0,0]', '[1,2]', '[1,2,3,4]', '[1,"a",3]', '[null,0,0]']
    c = []
    c += field_cases('camera.position', ok=['[0,1,6]', '[0,1,1e5]'], bad=vec_bad)
    c += field_cases('camera.look_at', ok=['[0,0,0]', '[1e5,0,0]'], bad=['[1e30,0,0]', '[0,1.1,3.0]', '[-1e30,0,0]'])
    c += field_cases('camera.up', ok=['[0,2,0]', '[1,1,0]', '[0,1e5,0]'],
                     bad=['[0,0,0]', '[0,1e-30,0]', '[1e20,1e20,0]', '[0,0.1,3]', '[0,-0.2,-6]'])
    c += field_cases('camera.fov_y', ok=['0.1', '179'], bad=['0', '180', '-1', '1e30'])
    c += field_cases('camera.resolution', ok=['[1,1]', '[7,3]'],
                     bad=['[0,32]', '[32,-1]', '[16384,16384]', '[20000,2]', '[1.5,2]', '[32]'])
    c += field_cases('render.max_depth', ok=['0', '1', '100000'], bad=['-1', '100001', '1.5', '2147483648'])
    c += field_cases('render.seed', ok=['0', '4294967295'], bad=['-1', '4294967296', '0.5'])
    c += field_cases('volumes.0.sigma_t_scale', ok=['0', '100'], bad=['-1', '1e7', '1e6'])
    c += field_cases('volumes.1.sigma_t_scale', ok=['0', '50'], bad=['1e6', '-0.1'])
    c += field_cases('volumes.0.albedo', ok=['[1,1,1]', '[0,0,0]'], bad=['[1.1,0,0]', '[-0.1,0,0]'])
    c += field_cases('volumes.0.g', ok=['0.999', '-0.999'], bad=['1', '-1', '2'])
    c += field_cases('volumes.0.transform.translate', ok=['[1e5,0,0]'], bad=['[1e30,0,0]', '[0,0,-1e7]'])
    c += field_cases('volumes.0.transform.scale', ok=['[2,2,2]', '[0.01,0.01,0.01]'], bad=['[0,1,1]', '[1e30,1,1]', '[-1,1,1]', '[1e-7,1,1]'])
    c += field_cases('volumes.0.transform.rotate_deg', ok=['[90,45,10]'], bad=['[1e30,0,0]'])
    c += field_cases('volumes.0.generator.resolution', ok=['8', '96'], bad=['1', '1025', '0', '-5'])
    c += [Case('generator 1024 over the memory budget', 'error', r'volumes\.0\.generator.*memory budget',
               ['volumes.0.generator.resolution=1024', 'volumes.0.generator.size=[1,1,1]', 'volumes.0.generator.type="constant"'])]
    c += field_cases('volumes.0.generator.size', ok=['[0.4,0.4,0.4]'], bad=['[1e6,1e-4,1e-4]', '[0,1,1]', '[1e7,1,1]', '[1,1,0.001]'])
    c += field_cases('volumes.0.generator.type', ok=['"plume"'], bad=['"smoke"', '""'], pattern='volumes.0.generator.type')
    c += field_cases('volumes.0.emission.intensity', ok=['0', '1000'], bad=['-1', '1e13', '1e30'])
    c += field_cases('volumes.0.emission.temperature_scale', ok=['0', '5000'], bad=['-1', '1e7'])
    c += field_cases('volumes.0.emission.mode', ok=['"none"'], bad=['"grid"', '"lava"'])
    c += field_cases('lights.0.intensity', ok=['0', '1e6'], bad=['-1', '1e13', '1e30'])
    c += field_cases('lights.0.color', ok=['[0,0,0]', '[1e6,1e6,1e6]'], bad=['[1e30,1e30,1e30]', '[-1,0,0]', '[1e7,0,0]'])
    c += [Case('light intensity x colour overflow', 'error', r'lights\.0\.intensity', ['lights.0.intensity=1e12', 'lights.0.color=[1e6,1,1]'])]
    def light(text):
        return ['lights=[{"type":"environment","intensity":0.02},' + text + ']']
    c += [Case('point light at 1e30', 'error', r'lights\.1\.position', light('{"type":"point","position":[1e30,0,0]}'))]
    c += [Case('point light 1e30 x 1e30', 'error', r'lights\.1\.', light('{"type":"point","position":[0,1,0],"intensity":1e30,"color":[1e30,1e30,1e30]}'))]
    c += [Case('directional light huge direction', 'error', r'lights\.1\.direction', light('{"type":"directional","direction":[3e19,-1e20,2e19]}'))]
    c += [Case('directional light zero direction', 'error', r'lights\.1\.direction', light('{"type":"directional","direction":[0,0,0]}'))]
    c += [Case('directional light scaled direction renders', 'render', '', light('{"type":"directional","direction":[3e5,-1e6,2e5]}'))]
    c += [Case('sphere light radius 0', 'error', r'lights\.1\.radius', light('{"type":"sphere","position":[0,1,0],"radius":0}'))]
    c += [Case('spot falloff beyond cone', 'error', r'lights\.1\.cone_falloff_deg',
               light('{"type":"spot","position":[0,2,0],"cone_angle_deg":10,"cone_falloff_deg":20}'))]
    c += [Case('spot light at 1e6 renders', 'render', '', light('{"type":"spot","position":[0,1e6,0],"direction":[0,-1,0],"intensity":1e12}'))]
    c += [Case('unknown light type', 'error', r'lights\.1\.type', light('{"type":"area"}'))]
    c += [Case('environment 1e30 x 1e30', 'error', r'lights\.0\.', ['lights.0.intensity=1e30', 'lights.0.color=[1e30,1e30,1e30]'])]
    c += [Case('unknown light field', 'error', r'lights\.0\.position', ['lights.0.position=[0,0,0]'])]
    c += field_cases('strategy.majorant.cell_size', ok=['1', '4096'], bad=['0', '4097'])
    c += field_cases('strategy.majorant.emission_weight', ok=['0', '1e9'], bad=['-1', '1e10'])
    c += [Case('emission weight 1e9 uncapped', 'render', '',
               ['strategy.preset="emission"', 'strategy.majorant.emission_weight=1e9', 'strategy.majorant.emission_cap=0'])]
    c += field_cases('strategy.majorant.emission_cap', ok=['0', '1000'], bad=['-1', '1001'])
    c += field_cases('strategy.guiding.probe_spacing', ok=['0', '0.5'], bad=['-1', '1e7'])
    c += [Case('probe spacing 0.001', 'error', r'strategy\.guiding\.probe_spacing', ['strategy.preset="full"', 'strategy.guiding.probe_spacing=0.001'])]
    c += field_cases('strategy.guiding.probe_radius', ok=['2'], bad=['10', '0'])
    c += field_cases('strategy.guiding.guided_probability', ok=['0.5'], bad=['0', '1'])
    c += field_cases('strategy.preset', ok=['"full"', '"equiangular"', '"emission"'], bad=['"fastest"'], junk=False)
    c += [Case('full with no light and no emission', 'render', '',
               ['strategy.preset="full"', 'lights=[]', 'volumes.0.emission.mode="none"'])]
    c += [Case('dense 1e6 x 1e6', 'error', r'volumes\.0\.sigma_t_scale',
               ['volumes.0.generator.type="constant"', 'volumes.0.generator.value=1e6', 'volumes.0.sigma_t_scale=1e6',
                'volumes.0.emission.mode="none"'])]
    c += [Case('nine volumes', 'error', r'volumes', ['volumes=' + json.dumps([{"generator": {"type": "constant"}}] * 9)])]
    c += [Case('volume with file and generator', 'error', r'volumes\.0', ['volumes.0.file="x.vdb"'])]
    c += [Case('missing VDB file', 'error', r'volumes\.0', ['volumes.0={"file":"nowhere.vdb"}'])]
    c += [Case('VDB file is a directory', 'error', r'volumes\.0.*directory', ['volumes.0={"file":"/tmp"}'])]
    c += [Case('VDB file is /dev/zero', 'error', r'volumes\.0.*device', ['volumes.0={"file":"/dev/zero"}'])]
    c += [Case('invalid UTF-8 name', 'error', r'UTF-8', ['volumes.0.name=\udcff\udcfe'])]
    c += [Case('set without =', 'error', r'key=value', ['camera.fov_y'])]
    c += [Case('set index out of range', 'error', r'volumes\.7', ['volumes.7.g=0'])]
    c += [Case('set inside a number', 'error', r'camera\.fov_y\.x', ['camera.fov_y.x=1'])]
    c += [Case('unknown top-level field', 'error', r'colour', ['colour=1'])]
    c += [Case('description nested 60000 deep', 'error', r'nest', ['description=' + '[' * 60000 + ']' * 60000])]
    c += [Case('camera nested 60000 deep', 'error', r'nest', ['camera=' + '[' * 60000 + ']' * 60000])]
    c += [Case('description of 100 KB renders', 'render', '', ['description="' + 'x' * 100000 + '"'])]
    c += [Case('huge array value', 'error', r'camera\.position', ['camera.position=[' + ','.join(['1'] * 50000) + ']'])]
    return c


def file_cases(work):
    """Whole scene files."""
    def scene_file(name, text=None, binary=None):
        path = os.path.join(work, 'files', name)

        def prepare():
            os.makedirs(os.path.dirname(path), exist_ok=True)
            if os.path.lexists(path):
                os.remove(path)
            if binary is not None:
                with open(path, 'wb') as f:
                    f.write(binary)
            else:
                with open(path, 'w', encoding='utf-8') as f:
                    f.write(text)
        return path, prepare

    minimal = '{"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [16, 16]}, "render": {"max_depth": 4}}'
    cases = []
    specs = [
        ('empty.json', '', 'not valid JSON'),
        ('null.json', 'null', r'top level'),
        ('array.json', '[]', r'top level'),
        ('string.json', '"scene"', r'top level'),
        ('truncated.json', minimal[:40], 'not valid JSON'),
        ('trailing.json', minimal + '}', 'not valid JSON'),
        ('comment.json', '// scene\n' + minimal, 'not valid JSON'),
        ('number-overflow.json', minimal.replace('"max_depth": 4', '"max_depth": 1e309'), 'not valid JSON'),
        ('float-overflow.json', minimal.replace('[0, 0, 3]', '[0, 0, 1e400]'), 'not valid JSON'),
        ('deep-camera.json', '{"camera": ' + '[' * 100000 + ']' * 100000 + '}', 'nest'),
        ('deep-volumes.json', '{"volumes": ' + '{"a":' * 50000 + '1' + '}' * 50000 + '}', 'nest'),
        ('deep-strategy.json', '{"strategy": ' + '[' * 100000 + ']' * 100000 + '}', 'nest'),
        ('missing-camera.json', '{}', r'camera'),
        ('camera-array.json', '{"camera": [1, 2, 3]}', r'camera'),
        ('volumes-object.json', minimal[:-1] + ', "volumes": {}}', r'volumes'),
        ('lights-string.json', minimal[:-1] + ', "lights": "sun"}', r'lights'),
        ('strategy-number.json', minimal[:-1] + ', "strategy": 3}', r'strategy'),
        ('duplicate-keys.json', minimal[:-1] + ', "render": {"max_depth": 2}}', None),
        ('minimal.json', minimal, None),
        ('nan-literal.json', minimal.replace('[0, 0, 3]', '[0, 0, NaN]'), 'not valid JSON'),
        ('infinity-literal.json', minimal.replace('[0, 0, 3]', '[0, 0, Infinity]'), 'not valid JSON'),
    ]
    for name, text, pattern in specs:
        path, prep = scene_file(name, text=text)
        cases.append(Case(f'file {name}', 'render' if pattern is None else 'error', pattern or '', scene=path, prepare=prep))
    for name, data, pattern in [
        ('binary.json', bytes(range(256)) * 4, 'not valid JSON'),
        ('invalid-utf8.json', minimal.replace('"render"', '"description": "\xff\xfe", "render"').encode('latin-1'), 'not valid JSON'),
        ('utf16.json', minimal.encode('utf-16'), 'not valid JSON'),
        ('bom.json', b'\xef\xbb\xbf' + minimal.encode(), None),
        ('nul-bytes.json', b'\0' * 1000, 'not valid JSON'),
    ]:
        path, prep = scene_file(name, binary=data)
        cases.append(Case(f'file {name}', 'error' if pattern else 'clean', pattern or '', scene=path, prepare=prep))

    big = os.path.join(work, 'files', 'huge.json')

    def make_big():
        os.makedirs(os.path.dirname(big), exist_ok=True)
        with open(big, 'wb') as f:
            f.truncate(65 << 20)
    cases.append(Case('file of 65 MB', 'error', '64 MB', scene=big, prepare=make_big))
    cases.append(Case('scene is /dev/zero', 'usage-or-error', r'/dev/zero', scene='/dev/zero'))
    cases.append(Case('scene is a directory', 'usage-or-error', r'directory|Directory|File does not exist|not a regular', scene=work))
    fifo = os.path.join(work, 'files', 'fifo.json')

    def make_fifo():
        os.makedirs(os.path.dirname(fifo), exist_ok=True)
        if os.path.lexists(fifo):
            os.remove(fifo)
        os.mkfifo(fifo)
    cases.append(Case('scene is a FIFO', 'usage-or-error', r'fifo\.json', scene=fifo, prepare=make_fifo))
    loop = os.path.join(work, 'files', 'loop.json')

    def make_loop():
        os.makedirs(os.path.dirname(loop), exist_ok=True)
        for p in (loop, loop + '2'):
            if os.path.lexists(p):
                os.remove(p)
        os.symlink(loop + '2', loop)
        os.symlink(loop, loop + '2')
    cases.append(Case('scene is a symlink loop', 'usage-or-error', r'loop\.json', scene=loop, prepare=make_loop))
    cases.append(Case('scene path too long', 'usage-or-error', r'aaaa', scene='/tmp/' + 'a' * 5000 + '.json'))
    cases.append(Case('scene does not exist', 'usage-or-error', r'nowhere', scene='/nowhere/scene.json'))
    return cases


def flag_cases():
    return [
        Case('--time nan', 'usage', r'--time', flags=['--time', 'nan'], sets=[]),
        Case('--time inf', 'usage', r'--time', flags=['--time', 'inf']),
        Case('--time -1', 'usage', r'--time', flags=['--time', '-1']),
        Case('--spp 0', 'usage', r'--spp', flags=['--spp', '0']),
        Case('--spp huge', 'usage', r'--spp', flags=['--spp', '99999999999']),
        Case('--threads -1', 'usage', r'--threads', flags=['--threads', '-1']),
        Case('--max-memory 0', 'usage', r'--max-memory', flags=['--max-memory', '0']),
        Case('--max-memory nan', 'usage', r'--max-memory', flags=['--max-memory', 'nan']),
        Case('--max-memory tiny', 'error', r'memory budget', flags=['--max-memory', '0.000001']),
        Case('--seed -5', 'usage', r'--seed', flags=['--seed', '-5']),
    ]


def vdb_cases(work, cli, hostile):
    vdir = os.path.join(work, 'vdb')
    expectations = {
        'ok': ('render', ''),
        'value-1e30': ('error', r'optical depth'),
        'value-max-float': ('error', r'optical depth'),
        'value-1e6': ('error', r'optical depth'),
        'value-nan': ('render', ''),
        'value-inf': ('render', ''),
        'value-negative': ('render', ''),
        'value-denormal': ('render', ''),
        'scale-1e30': ('error', r'voxels|transform'),
        'scale-1e9': ('error', r'voxels'),
        'translate-1e9': ('error', r'transform'),
        'far-voxels-1e9': ('error', r'indices|index'),
        'far-voxels-1e6': ('error', r'stray voxels'),
        'huge-tile': ('error', r'bounding box|stray'),
        'empty': ('render', ''),
        'no-grids': ('error', r'expected a grid named'),
        'wrong-name': ('error', r'expected a grid named "density"'),
        'vec3-density': ('error', r'expected float'),
        'int-density': ('error', r'expected float'),
        'double-density': ('render', ''),
        'double-1e300': ('render-warning', r'grid "density" had 1 NaN, infinite or negative values'),
        'bool-density': ('error', r'expected float'),
        'frustum': ('error', r'frustum'),
        'background-1': ('error', r'background'),
        'duplicate-names': ('render', ''),
        'level-set': ('render-warning', r'grid "density" is a level set .*rendered as the fog volume'),
        'level-set-unmarked': ('error', r'background value .*signed distance field'),
        'level-set-background-0': ('error', r'level set with background value 0'),
    }
    cases = []

    def scene_for(vdb, extra=None):
        doc = {"camera": {"position": [0.2, 0.2, 2.0], "look_at": [0.2, 0.2, 0.2], "resolution": [16, 16]},
               "render": {"max_depth": 4},
               "volumes": [dict({"file": os.path.basename(vdb), "sigma_t_scale": 2.0}, **(extra or {}))],
               "lights": [{"type": "directional", "direction": [0, -1, 0], "intensity": 2.0}]}
        path = vdb[:-4] + '.json'
        with open(path, 'w') as f:
            json.dump(doc, f)
        return path

    for kind, (expect, pattern) in expectations.items():
        vdb = os.path.join(vdir, f'{kind}.vdb')

        def prep(kind=kind, vdb=vdb):
            os.makedirs(vdir, exist_ok=True)
            subprocess.run([hostile, kind, vdb], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=120)
            scene_for(vdb)
        cases.append(Case(f'vdb {kind}', expect, pattern, scene=vdb[:-4] + '.json', prepare=prep))

    # Emission per unit length beyond the density's box: rendered, with a warning that names the grid.
    for kind, extra, grid in [
            ('flame-beyond-density', {"emission": {"mode": "grid", "units": "per_length"}, "emission_grid": "flame"}, 'emission grid "flame"'),
            ('temperature-beyond-density', {"emission": {"mode": "blackbody", "units": "per_length", "temperature_scale": 1500},
                                            "temperature_grid": "temperature"},
             'temperature grid "temperature"')]:
        vdb = os.path.join(vdir, f'{kind}.vdb')

        def prep(kind=kind, vdb=vdb, extra=extra):
            os.makedirs(vdir, exist_ok=True)
            subprocess.run([hostile, kind, vdb], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=120)
            scene_for(vdb, extra)
        cases.append(Case(f'vdb {kind}', 'render-warning', re.escape(grid) + r'.* reaches outside the density grid', scene=vdb[:-4] + '.json',
                          prepare=prep))

    # Inputs found by the fuzzer (tests/fuzz/fuzz_vdb.cpp), kept as regressions. huge-metadata-string:
    # a file-level metadata name length of 2 GB that OpenVDB allocated before failing (60 s, 4 GB).
    found = {
        'huge-metadata-string': 'IEJEVgAAAADgAAAACgAAAAAAAAABMWI4MTdlYzMtNWRmNC00YzkyLWE1NjItOGE4N2UxMmE5NSBCM2IAAAAAAgD2AAcAAABkZW5zaXR5'
                                'EAAAAFRyZWVfZmxvYXRfNV80XzMAAAAAfAAAAAAAAERWAAAAAOAAAAAKAAAAAAAAAAExYjgxN2VjMwAWJwAAAAAALTVkZjQtNGM5'
                                'Mi1hNTYyLThhODdlAEIoAAAAAAAABgAxMg==',
        # no grid offsets: OpenVDB read whole grids with corrupt counts (over 4 GB)
        'stream-without-offsets': 'IEJEVgAAAADgAAAACl7deIL+fwAAMWI4MTdlYzMtNWRmNC00YzkyLWE1NjItOGE4N2UxMmE5NTNiAAAAAAIAAAAHAAApAGRlAAAp'
                                  'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                  'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAABe3XiC/n8AAAAAAAAAAAAAAA==',
        # a UUID with a vertical tab in it: OpenVDB's formatted read skips it, so every later field
        # shifted by a byte and OpenVDB sized a string by 3 GB of garbage (98 s under ASan)
        'uuid-with-whitespace': 'IEJEVgAAAADgAAAACgAAAAAAAAABYjc1ZjAzMjMtZDIyNC00YTY3LTk2YjAtZTRhMDE2ZGVhC2I1NQAAAAACAAAABwAAAGRlbnNp'
                                'dHkQAAAAVHJlZV9mvLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLwAAAAAABYnAAAAAAAAQigAAAAA'
                                'AAAGAAAACAAAAAUAAABjbAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAPb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vYgQkRW'
                                'AAAAAOB6RgAAAD9nIHYAAAAAAAAAAAQAAAAAAAAAAABmbG9hdAAAAAAAADAAAAAAAABvbAB1bfYAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAABmbG9hdAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAHVt9gAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAGZsb2F0AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAADAAAAAAAAAAAAAAAAAAAAAAAAAAAAAABsb2F0XzVfNF8zAAAA'
                                'AHwAALy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8'
                                'vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8vLy8AAAAAAAWJwAAAAAAAEIoAAAAAAAABgAAAAgAAAAFAAAAY2wA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAD29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb29vb2IEJEVgAAAADgekYAAAA/ZyB2AAAA'
                                'AAAAAAAEAAAAAAAAAAAAZmxvYXQAAAAAAAAwAAAAAAAAb2wAdW32AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAZmxvYXQAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAB1bfYAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAABmbG9hdAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAwAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA'
                                'AAAA',
    }
    found = {kind: base64.b64decode(data) for kind, data in found.items()}
    # Larger inputs, zlib-compressed then base64. Two zip-compressed files whose tree holds a chunk
    # that claims to be stored uncompressed and longer than the node's values: OpenVDB 10 read it
    # past its buffer (a heap overflow under ASan, in an internal node's values; a float and a double
    # grid).
    zipped = {
        'double-chunk-past-buffer': 'eNrt2r1Kw1AUB/DU+oVUa1Fx6ZBJBwmITVI7KeLq5Mcab3JP5UI+SpKGVnDwDXwAF59CnXyVPoKTuOmNSbStgoI4CP8fXM7N4Zyb'
                                    'kztH3ds/UaSBXHNKpmTorGW2mo7GTc40nZGu2dTY1LaMpsm5zQ3OjLdCuWbk4uRHIu7X5PYoJLJ40LVdsgxLtxpp3UV+8MNaFuvr'
                                    'WSzn/fNytYXssO2gZ3msNyUTCTkNUZGbal71RaXwRyqHLRaVTuB1QooiEfjTMhfFofDPluTuXHTUDZU5sUhITZjbpahWNHFyWZ+4'
                                    '5QaMp++0ikyaWMk//V09jwtFu0eeZfdjitLxhB+b+qzcXN1Pjo6WBD1y5YBdPx4pLE9k56XlPvPoY+6h206v5dgX7SD0Dh3m0gHr'
                                    'ZF2PO38bB59iaezuv3sGAAAAAAAAAAAAAAAAAAAAAID/6Pklkz/uFn8Gjcef+m2/spzH3rVzqlxWnyqLA+Vmu66s3pbuXgGsRIGa',
        'float-chunk-past-buffer': 'eNrt2rlOw0AQBuCEcIkzCOhdQYEsEeJcFRGipeJoV2t7jFay15FtogRR8Ai8Cg3Pk0egoESCMbZDEiiQEAXS/ymrGa9mnPG6tXFy'
                                   'elViI14rpUy5TV6n4x3VzFrLskzLbjlmx3Ft06s1ZEO6brPZPvwo5LXEyyUdq2RY5fQiIhKeH8pENIQl6mnZXX7fp70sru5nsZK3'
                                   'r/PylE/CtsOBCORggTf65NTVGiebedU3lUpPVU6qFpVOGPQiimMV6kXei5NI6ettzm5VzzgwpJOoPhl96d9QvFU0ueTLIbmCn8NN'
                                   '/1MUO+nGbv7kYzt53CjaAwqEPUwoTsdTOmlay5w8PM5Pj9YPB+TzgDc6mSqszGX3S8u1DOhz7onDTo/lUisvjIJzR/p0JntZ1/Px'
                                   '38bRlzh5GOWZ9zB7DTgXAAAAAAAAAAAAAAAAAAAAAPiPXt8ynHaLr19m40/9tr/0Mh7mPv2Mqcu/7juy1oM8',
        # a ScaleMap of scale 1e-30 or so: OpenVDB threw while building its affine form, past the loader
        'scale-map-nearly-singular': 'eNrt3M9KG0EcB/CNWlskrYZavOSwULCFEihmNzFeWorXntRex9mdn+3A/gmZzZIIhfoGPkAvfQrbU32UfQRP0lucze5qYotFklCx'
                                     '3w8Mv5nhN5vJb3aua77b/mBoiW5LRqZkW7zVaDXdmmgIXrM4WTWH6q9rG3azIYQjbMHtYaJuD3UTFCgZ9Su6u9shYiLsOh4xm1ms'
                                     'nuZ9zh/8cz2L1RdZnM/XP9btQOoVjhP2mM97D/RETG5dlnVnOc/6Q6YMxjJHrRSZbui3O6SUDINFPaeijgw+PtW9Q9k2X5ncjWRM'
                                     'Zsy9LqlKsUiQx/skmBdykf4mK2bSiWf5X79UzeOTYrlPPnP6Eal0ezKIGtYj3Tn+sTC+tTjskac32A2iscT5uex5aXrAfbra90i1'
                                     '07LsBfIg7Pg7LvfoPW9nq87e5ONiOJuY/BZL147gb+Nb2zJgIiZu+/277ffumgMA7hPA3XKOEgAAAAAAAAAAAAAAQOE5SgAAAAAA'
                                     'AAAAMGVSMcVjEowr9unO7OolDuZ2SnOoAQAA/F9OT78MY5JknUR3hhNngwGqAwAAAAAwU78GmXz4tvguw/U4Lfjuw78w61Odxqt3'
                                     'g9U89r66+8bR8nl5JTG+bVaNtZPS98lf2YmLc9P2LgDJbhfu',
        # a vec4i metadata entry of 12 bytes: OpenVDB reads 16 whatever the entry says, and then sized a
        # metadata name by 1.7 GB of garbage (8 GB peak, 43 s)
        'vec4i-of-12-bytes': 'eNrt2stOwkAUBuBWvMWgSNS4YcFKF4bESFtkpTFuXXnZ1mnnYCbphdBCiokL38AHcONTqCtfhUdwZdzplBYFNLggJl7+L5mc6eSc'
                             '9nQ67Cju7Z8oUkeOOSWh6hqrGtWKXeIGZyWNkVayqLxZ2tIrBucW1znTu4lyzMjByQtE2M7L6VGDyOR+03LI1E3NLMd5F+mNH9aS'
                             'WFhPYiatn5ejJmSFZfmR6bJoSi60yNZEVk5yadYnmcJLM8vdzH6LvUzbd+sNCgLhe9NyLQgbwjtbkrNzUS9uFJkdihYVW8xpUpDv'
                             'FXFyWJu46fiMx880eyvxwkr66m8KaVzolbvkmlY7pCBuT3ihoc3KydX95GBrLT8iRzbY9MKBxMxEcr843WMuvffdt9vxthx7ouY3'
                             '3EObOXTA6knV4873xs6HqA7t/VfXAAAAAAAAAAAAAAAAAAAAAAAAAADwy+APoYDz8Y89vyTSy1116MOrOFB/6Ges/qSvMHT0RlhO'
                             'Y3RtnyqXuafsYke52S4oq7fq3fhHduzNGdXeK4a/kL4=',
        # a root tile whose active flag is the byte 231: OpenVDB reads it into a bool (UBSan: not a valid
        # value for type bool, in the double grid's conversion to float)
        'root-tile-active-flag-231': 'eNrt271u01AUwHGH8iVUSCuoWDJkggFFAmKndAJVXSsGSldz7XuKruSPKHaipBIDb8AOC08BTLxKNtZOFVu4rh2alKoZChJS/j/p'
                                     '6txcnWMfn8lD3Nze2XessV23nFLNc9VWZ2szbOmOVi1XidsKpP249dTb7GgdaE8r7yTRrht2aUkyk4/W7XavJ+LrtB9E4nu+67eL'
                                     'vHfVhb8/KGPjYRlXqvrbdh0YWxEE6dCP1fCaPRhI2DardlOvss7JNMlc5qy1aWaYxt2eZJlJk+v2LMt7Jnl71+4OTbf5qKnC3Ayk'
                                     'OVBRX7L1aZGWSI1E+1GqdHFPf3pSHGxUj/5bo4p3puWxxH4wyiUr2jNJ3nFv2s2Hb1fnWxukQ4lsg/0kn0tcuVJer0hPVCynfc9M'
                                     'uxjL68QcpL34Vagi2VXdsuro+cVxzqLkRXH8R6yducOi3wD+mUmdGQAAAADL7OMsxgEsmx9/A2MEAAAAAAC42OTE3ksmAQAAAAAA'
                                     'AAAAsEz4YB4AAJx9L6j9T+8JP8v/tEwWZ96r4vBT+MZ5Xz9eXRs7n580nPtfal+dF5d9uEsP59z2npXt/QK9h9ZN',
    }
    found.update({kind: zlib.decompress(base64.b64decode(data)) for kind, data in zipped.items()})
    for kind, data in found.items():
        vdb = os.path.join(vdir, f'fuzz-{kind}.vdb')

        def prep(data=data, vdb=vdb):
            os.makedirs(vdir, exist_ok=True)
            open(vdb, 'wb').write(data)
            scene_for(vdb)
        cases.append(Case(f'vdb fuzz finding {kind}', 'error', r'corrupt|offsets|UUID|degenerate', scene=vdb[:-4] + '.json', prepare=prep))

    # A valid generated VDB, truncated and bit-flipped.
    source = os.path.join(vdir, 'source.vdb')

    def make_source():
        os.makedirs(vdir, exist_ok=True)
        if not os.path.exists(source):
            subprocess.run([cli, 'generate', 'torch', '-o', source, '--resolution', '24'], check=True, stdout=subprocess.DEVNULL, timeout=120)
    for fraction in [0.0, 0.01, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999]:
        vdb = os.path.join(vdir, f'truncated-{fraction}.vdb')

        def prep(fraction=fraction, vdb=vdb):
            make_source()
            data = open(source, 'rb').read()
            open(vdb, 'wb').write(data[:int(len(data) * fraction)])
            scene_for(vdb, {"emission": {"mode": "blackbody", "temperature_scale": 1500}, "temperature_grid": "temperature"})
        cases.append(Case(f'vdb truncated to {fraction:.1%}', 'error', r'volumes\.0', scene=vdb[:-4] + '.json', prepare=prep))
    for seed in range(32):
        vdb = os.path.join(vdir, f'flipped-{seed}.vdb')

        def prep(seed=seed, vdb=vdb):
            make_source()
            data = bytearray(open(source, 'rb').read())
            rng = random.Random(seed)
            # Flips in the header and grid descriptors (first 2 KB) do the most damage; spread the rest.
            for _ in range(1 + seed % 4):
                pos = rng.randrange(min(len(data), 2048)) if seed % 2 == 0 else rng.randrange(len(data))
                data[pos] ^= 1 << rng.randrange(8)
            open(vdb, 'wb').write(bytes(data))
            scene_for(vdb, {"emission": {"mode": "blackbody", "temperature_scale": 1500}, "temperature_grid": "temperature"})
        cases.append(Case(f'vdb bit flip {seed}', 'clean', r'volumes\.0', scene=vdb[:-4] + '.json', prepare=prep))
    return cases


def run_case(case, args, default_scene):
    scene = case.scene or default_scene
    out = os.path.join(args.work, 'out.exr')
    if os.path.exists(out):
        os.remove(out)
    cmd = [args.cli, 'render', scene, '-o', out, '--threads', '1']
    if '--spp' not in case.flags and '--time' not in case.flags:
        cmd += ['--spp', '2']
    cmd += case.flags
    if case.scene is None:
        cmd += ['--set', 'camera.resolution=[32,32]']
    for s in case.sets:
        cmd += ['--set', s]
    memory = int(args.memory_gb * (1 << 30))

    def limits():
        if memory > 0:
            resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    start = time.time()
    try:
        # surrogateescape: the invalid-UTF-8 case passes raw bytes through argv.
        p = subprocess.run([c.encode('utf-8', 'surrogateescape') for c in cmd], capture_output=True, timeout=args.timeout,
                           preexec_fn=limits, env=dict(os.environ))
    except subprocess.TimeoutExpired:
        return False, f'hung (killed after {args.timeout} s)', time.time() - start
    seconds = time.time() - start
    err = p.stderr.decode('utf-8', 'replace') + p.stdout.decode('utf-8', 'replace')
    first = err.strip().splitlines()[0][:300] if err.strip() else ''
    if p.returncode < 0:
        return False, f'crashed with signal {-p.returncode}: {first}', seconds
    scene_name = os.path.basename(scene)[:60]

    def named_error():
        m = re.search(r'^error: (.*)$', p.stderr.decode('utf-8', 'replace'), re.M)
        return m is not None and scene_name in m.group(1) and re.search(case.pattern, m.group(1)) is not None
    if case.expect == 'render':
        ok = p.returncode == 0 and os.path.exists(out)
    elif case.expect == 'render-warning':  # renders, and says how it read the input
        ok = p.returncode == 0 and os.path.exists(out) and re.search(r'^warning: .*' + case.pattern, err, re.M) is not None
    elif case.expect == 'error':
        ok = p.returncode == 2 and named_error()
    elif case.expect == 'clean':
        ok = (p.returncode == 0 and os.path.exists(out)) or (p.returncode == 2 and named_error())
    elif case.expect == 'usage':
        ok = p.returncode not in (0,) and re.search(case.pattern, err) is not None and 'Traceback' not in err
    else:  # usage-or-error: refused by CLI11's file check or by the loader, naming the file either way
        ok = p.returncode != 0 and re.search(case.pattern, err) is not None
    return ok, f'exit {p.returncode}: {first}', seconds


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--cli', required=True)
    ap.add_argument('--hostile-vdb', required=True)
    ap.add_argument('--scene', required=True)
    ap.add_argument('--work', required=True)
    ap.add_argument('--filter', default='')
    ap.add_argument('--timeout', type=float, default=60.0)
    ap.add_argument('--memory-gb', type=float, default=6.0, help='address-space limit per case (0: none, e.g. under ASan)')
    ap.add_argument('--peak-mb', type=int, default=2048, help='largest RSS any case may reach (MB)')
    ap.add_argument('--list', action='store_true')
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    cases = set_cases() + file_cases(args.work) + flag_cases() + vdb_cases(args.work, args.cli, args.hostile_vdb)
    cases = [c for c in cases if args.filter in c.name]
    if args.list:
        for c in cases:
            print(f'{c.expect:8s} {c.name[:100]}')
        print(f'{len(cases)} cases')
        return 0
    failures = 0
    total = time.time()
    slowest = (0.0, '')
    # Peak RSS: the children's maximum only grows, so a case that raises it set a new peak.
    peak = (resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, 'before the first case')
    for c in cases:
        if c.prepare:
            c.prepare()
        ok, what, seconds = run_case(c, args, args.scene)
        rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        if rss > peak[0]:
            peak = (rss, c.name[:60])
            if ok and rss > args.peak_mb * 1024:
                ok, what = False, f'{what} (peak RSS {rss // 1024} MB, above {args.peak_mb} MB)'
        slowest = max(slowest, (seconds, c.name[:60]))
        if not ok:
            failures += 1
            print(f'FAIL [{c.expect}] {c.name[:100]}: {what}')
        elif os.environ.get('CANDELA_VERBOSE'):
            print(f'ok   [{c.expect}] {c.name[:100]}: {what[:160]} ({seconds:.2f} s)')
    print(f'{len(cases) - failures} of {len(cases)} cases as expected in {time.time() - total:.0f} s '
          f'(slowest {slowest[0]:.1f} s: {slowest[1]}; peak RSS {peak[0] // 1024} MB: {peak[1]})')
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
