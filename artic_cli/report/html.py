"""The report as a page to look at and listen to: ``paper.html`` rendered from the very text of ``paper.md``
(one source, no second copy of any number) with a summary of agreeing and differing rows per section, a table
of contents, every figure inline, every WAV as an audio player beside its link, and each verdict marked.  The
page stands alone on the file system: relative links, an inline style sheet, no script, no font, no server."""

from __future__ import annotations

import html
import re
from pathlib import Path

import markdown

STYLE = """
body { font: 15px/1.45 system-ui, sans-serif; max-width: 1100px; margin: 0 auto; padding: 1em 2em; color: #222; }
h1 { font-size: 1.6em; } h2 { margin-top: 2em; border-bottom: 2px solid #ddd; }
table { border-collapse: collapse; width: 100%; margin: 1em 0; font-size: 0.92em; }
th, td { border: 1px solid #ddd; padding: 0.3em 0.5em; vertical-align: top; text-align: left; }
th { background: #f3f3f3; }
td.agrees { background: #e9f7ec; } td.differs { background: #fde8e6; } td.open { background: #f5f5f5; }
td.agrees::before { content: "\\2714  "; color: #1a7f37; } td.differs::before { content: "\\2716  "; color: #c62828; }
img { max-width: 100%; height: auto; border: 1px solid #eee; }
audio { vertical-align: middle; height: 2em; margin: 0.2em 0.5em; }
.summary td, .summary th { text-align: right; } .summary td:first-child { text-align: left; }
nav.toc { background: #fafafa; border: 1px solid #eee; padding: 0.5em 1em; }
"""

_WAV = re.compile(r'<a href="([^"]+\.wav)">([^<]*)</a>')
_VERDICT = re.compile(r"<td>(agrees|differs|not compared)")


def _sections(body: str) -> list[tuple[str, str, int, int]]:
    """(anchor, title, rows agreeing, rows differing) of every h2 section of the rendered body."""
    out = []
    parts = re.split(r'<h2 id="([^"]+)">(.*?)</h2>', body)
    for k in range(1, len(parts), 3):
        text = parts[k + 2]
        out.append((parts[k], parts[k + 1], text.count('<td class="agrees">'), text.count('<td class="differs">')))
    return out


def _summary(sections: list[tuple[str, str, int, int]]) -> str:
    rows = "".join(f'<tr><td><a href="#{a}">{t}</a></td><td>{n_ok}</td><td>{n_bad}</td></tr>'
                   for a, t, n_ok, n_bad in sections)
    ok, bad = sum(s[2] for s in sections), sum(s[3] for s in sections)
    return ('<table class="summary"><thead><tr><th>section</th><th>rows that agree</th><th>rows that differ</th>'
            f"</tr></thead><tbody>{rows}<tr><th>all</th><th>{ok}</th><th>{bad}</th></tr></tbody></table>")


def _players(body: str) -> str:
    """Every link to a WAV with an audio player before it."""
    return _WAV.sub(lambda m: f'<audio controls preload="metadata" src="{m.group(1)}"></audio>'
                              f'<a href="{m.group(1)}">{m.group(2)}</a>', body)


def _document(title: str, body: str) -> str:
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n")


def to_html(md_text: str, title: str = "artic beside Dang & Honda (2004)") -> str:
    """The page of a report's markdown text."""
    conv = markdown.Markdown(extensions=["tables", "toc"])
    body = conv.convert(md_text)
    body = _VERDICT.sub(lambda m: f'<td class="{"open" if m.group(1) == "not compared" else m.group(1)}">{m.group(1)}',
                        body)
    body = _players(body)
    head, sep, rest = body.partition("</p>")  # after the report's opening paragraph: summary and contents
    top = (f"<h2>Summary</h2>{_summary(_sections(body))}"
           f'<nav class="toc"><strong>Contents</strong>{conv.toc}</nav>')
    return _document(title, head + sep + top + rest if sep else top + body)


def utterance_page(name: str, wav: str, picture: str, animation: str | None, rows: list[tuple[str, str, str, str]],
                   textgrid: str) -> str:
    """One spoken utterance's page: its sound, its spectrogram with formant tracks, tiers and movement, its
    animation, and a table of its segments (label, start, duration, how its forces were found); the file names
    are relative to the page."""
    table = "\n".join(["| segment | start (s) | duration (ms) | forces |", "|---|---|---|---|"]
                      + [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows])
    text = "\n".join([f"# /{name}/", "", f"Listen: [{Path(wav).name}]({wav}) (segments: [{Path(textgrid).name}]"
                      f"({textgrid}), a Praat TextGrid)", "", f"![/{name}/: spectrogram, formant tracks, segments, "
                      "tip / dorsum / jaw heights](" + picture + ")", ""]
                     + ([f"![/{name}/: the midsagittal view moving]({animation})", ""] if animation else [])
                     + [table, ""])
    return _document(f"/{name}/", _players(markdown.markdown(text, extensions=["tables"])))
