"""A tiny SVG line plot (log-log panels side by side), so that the README's plots need no plotting library."""

from __future__ import annotations

import math
from pathlib import Path

COLOURS = ("#1f5fa8", "#c0392b", "#2e8b57", "#8e44ad")


def _ticks(low: float, high: float) -> list[float]:
    return [10.0**k for k in range(math.floor(math.log10(low)), math.ceil(math.log10(high)) + 1)]


def _label(v: float) -> str:
    return f"{v:g}" if 1e-3 <= v < 1e4 else f"1e{round(math.log10(v))}"


def loglog_panels(panels: list[dict], path: Path, width: int = 460, height: int = 320) -> Path:
    """Write panels side by side as one SVG file.

    Each panel: ``title``, ``xlabel``, ``ylabel``, ``series`` (list of ``(name, xs, ys)``, positive values; NaN
    points are skipped), optional ``xreverse``. Returns ``path``.
    """
    m = {"l": 64, "r": 16, "t": 30, "b": 46}
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width * len(panels)}" height="{height}" '
        'font-family="sans-serif" font-size="12">',
        f'<rect width="{width * len(panels)}" height="{height}" fill="white"/>',
    ]
    for p, panel in enumerate(panels):
        x0 = p * width
        points = [(x, y) for _, xs, ys in panel["series"] for x, y in zip(xs, ys, strict=True) if x > 0 and y > 0]
        xl, xh = min(x for x, _ in points), max(x for x, _ in points)
        yl, yh = min(y for _, y in points), max(y for _, y in points)
        xt, yt = _ticks(xl, xh), _ticks(yl, yh)
        lx0, lx1, ly0, ly1 = math.log10(xt[0]), math.log10(xt[-1]), math.log10(yt[0]), math.log10(yt[-1])
        pw, ph = width - m["l"] - m["r"], height - m["t"] - m["b"]

        rev = panel.get("xreverse", False)

        def sx(v, lx0=lx0, lx1=lx1, pw=pw, x0=x0, rev=rev):
            f = (math.log10(v) - lx0) / (lx1 - lx0)
            return x0 + m["l"] + pw * ((1 - f) if rev else f)

        def sy(v, ly0=ly0, ly1=ly1, ph=ph):
            return m["t"] + ph * (1 - (math.log10(v) - ly0) / (ly1 - ly0))

        out.append(f'<text x="{x0 + width / 2}" y="18" text-anchor="middle" font-weight="bold">{panel["title"]}</text>')
        out.append(f'<rect x="{x0 + m["l"]}" y="{m["t"]}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>')
        for v in xt:
            out.append(f'<line x1="{sx(v):.1f}" x2="{sx(v):.1f}" y1="{m["t"]}" y2="{m["t"] + ph}" stroke="#ddd"/>')
            out.append(f'<text x="{sx(v):.1f}" y="{m["t"] + ph + 16}" text-anchor="middle">{_label(v)}</text>')
        for v in yt:
            out.append(
                f'<line x1="{x0 + m["l"]}" x2="{x0 + m["l"] + pw}" y1="{sy(v):.1f}" y2="{sy(v):.1f}" stroke="#ddd"/>'
            )
            out.append(f'<text x="{x0 + m["l"] - 6}" y="{sy(v) + 4:.1f}" text-anchor="end">{_label(v)}</text>')
        out.append(f'<text x="{x0 + m["l"] + pw / 2}" y="{height - 10}" text-anchor="middle">{panel["xlabel"]}</text>')
        out.append(
            f'<text x="{x0 + 16}" y="{m["t"] + ph / 2}" text-anchor="middle" '
            f'transform="rotate(-90 {x0 + 16} {m["t"] + ph / 2})">{panel["ylabel"]}</text>'
        )
        for k, (name, xs, ys) in enumerate(panel["series"]):
            colour = COLOURS[k % len(COLOURS)]
            pts = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in zip(xs, ys, strict=True) if x > 0 and y > 0)
            out.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="2"/>')
            for x, y in zip(xs, ys, strict=True):
                if x > 0 and y > 0:
                    out.append(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="3" fill="{colour}"/>')
            ly = m["t"] + 16 + 16 * k
            lx = x0 + m["l"] + pw - 110
            out.append(
                f'<line x1="{lx}" x2="{lx + 18}" y1="{ly - 4}" y2="{ly - 4}" stroke="{colour}" stroke-width="2"/>'
            )
            out.append(f'<text x="{lx + 24}" y="{ly}">{name}</text>')
    out.append("</svg>")
    path = Path(path)
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path
