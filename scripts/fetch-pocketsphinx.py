#!/usr/bin/env python3
"""Fetches CMU PocketSphinx 5.1.0's source package from PyPI (its C sources and US English
models, BSD) and unpacks it where faceanim's build looks for it, for machines without Debian's
libpocketsphinx (macOS, Windows, other Linux). `scripts/setup.sh libraries` runs it there.

The package is checked against its published sha256 before anything is unpacked; the folder
appears whole or not at all (unpacked beside it, then renamed). Where it is already there,
nothing is fetched.

Usage: scripts/fetch-pocketsphinx.py [FOLDER]
  FOLDER: default FACEANIM_POCKETSPHINX_SOURCE, else $XDG_DATA_HOME/faceanim/pocketsphinx-5.1.0
  (~/.local/share/… without it, %LOCALAPPDATA%\\faceanim\\… on Windows), where the build
  script of crates/sphinx-sys looks.
"""
import hashlib
import html.parser
import os
import pathlib
import sys
import tarfile
import tempfile
import urllib.parse
import urllib.request

PACKAGE = "pocketsphinx-5.1.0.tar.gz"
SHA256 = "982778456a9c7658294c2c8998acf66daeb4e4ca5e1f342afd71de2c36b519ab"
FOLDER = "pocketsphinx-5.1.0"


def default_folder():
    chosen = os.environ.get("FACEANIM_POCKETSPHINX_SOURCE")
    if chosen:
        return pathlib.Path(chosen)
    if os.environ.get("XDG_DATA_HOME"):
        base = pathlib.Path(os.environ["XDG_DATA_HOME"])
    elif os.environ.get("HOME"):
        base = pathlib.Path(os.environ["HOME"]) / ".local" / "share"
    elif os.environ.get("LOCALAPPDATA"):
        base = pathlib.Path(os.environ["LOCALAPPDATA"])
    else:
        sys.exit("fetch-pocketsphinx: no HOME, XDG_DATA_HOME or LOCALAPPDATA to put it in: give a folder")
    return base / "faceanim" / FOLDER


class Links(html.parser.HTMLParser):
    """The hrefs of a PEP 503 simple index page."""

    def __init__(self):
        super().__init__()
        self.hrefs = []

    def handle_starttag(self, tag, attrs):
        if tag == "a":
            self.hrefs.extend(v for k, v in attrs if k == "href" and v)


def package_url():
    index = os.environ.get("PIP_INDEX_URL", "https://pypi.org/simple").rstrip("/")
    page_url = f"{index}/pocketsphinx/"
    with urllib.request.urlopen(page_url, timeout=60) as page:
        links = Links()
        links.feed(page.read().decode("utf-8", "replace"))
    for href in links.hrefs:
        url = urllib.parse.urljoin(page_url, href)
        if urllib.parse.urlparse(url).path.endswith("/" + PACKAGE):
            return url.split("#", 1)[0]
    sys.exit(f"fetch-pocketsphinx: {page_url} lists no {PACKAGE}")


def safe_members(archive, into):
    """Every member, refusing links and paths that leave `into` (what tarfile's "data" filter
    refuses, on every Python 3)."""
    root = os.path.realpath(into)
    for member in archive.getmembers():
        target = os.path.realpath(os.path.join(into, member.name))
        if not (target == root or target.startswith(root + os.sep)):
            sys.exit(f"fetch-pocketsphinx: {PACKAGE}: {member.name} leaves the folder")
        if not (member.isfile() or member.isdir()):
            sys.exit(f"fetch-pocketsphinx: {PACKAGE}: {member.name} is not a plain file")
        yield member


def main():
    folder = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else default_folder()
    if (folder / "src" / "pocketsphinx.c").is_file():
        print(f"fetch-pocketsphinx: {folder} is there")
        return
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        sys.exit(f"fetch-pocketsphinx: {folder} is there and holds no PocketSphinx sources: move it away or give another folder")
    folder.parent.mkdir(parents=True, exist_ok=True)
    url = package_url()
    print(f"fetch-pocketsphinx: fetching {url}")
    with tempfile.TemporaryDirectory(dir=folder.parent, prefix=".pocketsphinx-") as work:
        package = pathlib.Path(work) / PACKAGE
        digest = hashlib.sha256()
        with urllib.request.urlopen(url, timeout=600) as response, open(package, "wb") as out:
            while chunk := response.read(1 << 20):
                digest.update(chunk)
                out.write(chunk)
        if digest.hexdigest() != SHA256:
            sys.exit(f"fetch-pocketsphinx: {url}: sha256 {digest.hexdigest()}, expected {SHA256}")
        unpacked = pathlib.Path(work) / "unpacked"
        with tarfile.open(package) as archive:
            archive.extractall(unpacked, members=list(safe_members(archive, unpacked)))
        source = unpacked / FOLDER
        if not (source / "src" / "pocketsphinx.c").is_file():
            sys.exit(f"fetch-pocketsphinx: {PACKAGE} holds no {FOLDER}/src/pocketsphinx.c")
        if folder.exists():
            folder.rmdir()
        os.replace(source, folder)
    print(f"fetch-pocketsphinx: unpacked into {folder}")


if __name__ == "__main__":
    main()
