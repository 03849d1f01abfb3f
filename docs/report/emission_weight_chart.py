#!/usr/bin/env python3
"""Draws docs/report/emission-weight-sweep.svg from emission-weight-sweep.csv (README, "The auto
strategy"): per scene, efficiency 1 / (variance x time) of each relative emission weight, the mean
variance and time over seeds, scaled so that the scene's best value is 1; relMSE-like (relative
variance) on the left, MSE-like (variance) on the right. Standard library only."""
import csv, math, os, collections

here = os.path.dirname(os.path.abspath(__file__))
data = collections.defaultdict(list)
with open(os.path.join(here, 'emission-weight-sweep.csv')) as f:
    for r in csv.DictReader(f):
        data[(r['scene'], float(r['relative_k']))].append(
            (float(r['relative_variance_per_sample']), float(r['variance_per_sample']), float(r['render_seconds'])))
scenes = sorted({s for s, _ in data})
ks = sorted({k for _, k in data})
colours = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#ff7f0e']
W, H, left, top, pw, ph, gap = 900, 300, 60, 30, 330, 220, 70
out = [f"<svg xmlns='http://www.w3.org/2000/svg' width='{W}' height='{H}' font-family='sans-serif' font-size='12'>",
       f"<rect width='{W}' height='{H}' fill='white'/>"]
def x_of(k, x0):
    return x0 + pw * (math.log(k) - math.log(ks[0])) / (math.log(ks[-1]) - math.log(ks[0]))
for panel, (title, index) in enumerate([('relMSE', 0), ('MSE', 1)]):
    x0 = left + panel * (pw + gap)
    out.append(f"<text x='{x0}' y='18'>{title} efficiency (each scene's best = 1)</text>")
    for i in range(5):
        v = i / 4
        y = top + ph * (1 - v)
        out.append(f"<line x1='{x0}' x2='{x0 + pw}' y1='{y}' y2='{y}' stroke='#ddd'/>")
        out.append(f"<text x='{x0 - 6}' y='{y + 4}' text-anchor='end'>{v:.2f}</text>")
    for k in ks:
        x = x_of(k, x0)
        out.append(f"<line x1='{x}' x2='{x}' y1='{top}' y2='{top + ph}' stroke='#eee'/>")
        out.append(f"<text x='{x}' y='{top + ph + 16}' text-anchor='middle'>{k:g}</text>")
    out.append(f"<text x='{x0 + pw / 2}' y='{top + ph + 34}' text-anchor='middle'>relative emission weight k</text>")
    for si, s in enumerate(scenes):
        eff = {}
        for k in ks:
            v = data[(s, k)]
            var = sum(x[index] for x in v) / len(v)
            t = sum(x[2] for x in v) / len(v)
            eff[k] = 1.0 / (var * t)
        best = max(eff.values())
        pts = ' '.join(f"{x_of(k, x0):.1f},{top + ph * (1 - eff[k] / best):.1f}" for k in ks)
        c = colours[si % len(colours)]
        out.append(f"<polyline points='{pts}' fill='none' stroke='{c}' stroke-width='2'/>")
        if panel == 1:
            out.append(f"<text x='{x0 + pw + 8}' y='{top + 14 + 16 * si}' fill='{c}'>{s}</text>")
out.append('</svg>')
with open(os.path.join(here, 'emission-weight-sweep.svg'), 'w') as f:
    f.write('\n'.join(out) + '\n')
