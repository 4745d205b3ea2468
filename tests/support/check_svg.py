#!/usr/bin/env python3
"""Checks the SVG that doorbench writes: every .svg file, and every <svg> element inside an
.html file, under the paths given (files or folders, searched recursively).

Each SVG must parse as XML (xml.etree), carry no stray text between its elements, and have
a complete legend: a legend entry is a <text> right of the data area (the largest <rect>
with fill="none"); it must follow a <line> (its key) whose stroke is the colour of the
series whose <title> is the entry's text, and every titled series must have its entry. A
series is a <polyline> (a line, an interval, a marker), a <polygon> (a band) or a <g> of
points, each with its <title> and stroke.

Usage: check_svg.py PATH...
Prints one line per problem, then "checked N SVG, M legend entries"; exit status 0 when no
problem was found and at least one SVG was checked, 1 otherwise.
"""
import pathlib
import re
import sys
import xml.etree.ElementTree as ET

SVG = "{http://www.w3.org/2000/svg}"


def svg_texts(path):
    """(name, text) of each SVG in the file: the file itself or the <svg> elements of HTML."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".svg":
        yield str(path), text
        return
    for index, match in enumerate(re.finditer(r"<svg\b.*?</svg>", text, re.S), start=1):
        yield f"{path} (svg {index})", match.group(0)


def number(element, name, default):
    try:
        return float(element.get(name, default))
    except ValueError:
        return default


def stray_text(name, root, problems):
    for parent in root.iter():
        if parent.tag not in (SVG + "svg", SVG + "g"):
            continue
        if parent.text and parent.text.strip():
            problems.append(f"{name}: stray text in <svg>: {parent.text.strip()[:80]!r}")
        for child in parent:
            if child.tail and child.tail.strip():
                tag = child.tag.replace(SVG, "")
                problems.append(f"{name}: stray text after <{tag}>: {child.tail.strip()[:80]!r}")


def legend(name, root, problems):
    """Checks the legend's entries; returns how many there are."""
    areas = [r for r in root.iter(SVG + "rect") if r.get("fill") == "none"]
    if not areas:
        return 0
    area = max(areas, key=lambda r: number(r, "width", 0) * number(r, "height", 0))
    right = number(area, "x", 0) + number(area, "width", 0)
    colours = {}
    for tag in ("polyline", "polygon", "g"):
        for series in root.iter(SVG + tag):
            title = series.find(SVG + "title")
            if title is not None and title.text:
                colours[title.text] = series.get("stroke")
    children = list(root)
    labels = []
    for index, element in enumerate(children):
        if element.tag != SVG + "text" or number(element, "x", float("-inf")) <= right:
            continue
        label = element.text or ""
        labels.append(label)
        key = children[index - 1] if index > 0 else None
        if key is None or key.tag != SVG + "line":
            problems.append(f"{name}: legend entry {label!r} has no <line> key before it")
        elif label not in colours:
            problems.append(f"{name}: legend entry {label!r} names no series (no <polyline>, "
                            "<polygon> or <g> with that <title>)")
        elif key.get("stroke") != colours[label]:
            problems.append(f"{name}: legend entry {label!r} has stroke {key.get('stroke')!r}, "
                            f"its series {colours[label]!r}")
    for label in colours:
        if label not in labels:
            problems.append(f"{name}: series {label!r} has no legend entry")
    return len(labels)


def main(paths):
    problems = []
    svgs = entries = 0
    files = []
    for given in map(pathlib.Path, paths):
        if given.is_dir():
            files += sorted(p for p in given.rglob("*") if p.suffix in (".svg", ".html"))
        elif given.exists():
            files.append(given)
        else:
            problems.append(f"{given}: no such file or folder")
    for path in files:
        for name, text in svg_texts(path):
            svgs += 1
            try:
                root = ET.fromstring(text)
            except ET.ParseError as error:
                problems.append(f"{name}: not XML: {error}")
                continue
            if root.tag != SVG + "svg":
                problems.append(f"{name}: the root element is {root.tag}, not svg")
                continue
            stray_text(name, root, problems)
            entries += legend(name, root, problems)
    for problem in problems:
        print(problem)
    print(f"checked {svgs} SVG, {entries} legend entries")
    return 1 if problems or svgs == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
