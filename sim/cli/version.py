"""``go2-wbc --version``: the installed distribution's version, licence and home, from its
metadata (so a wheel and an editable install say what pip installed)."""

from __future__ import annotations

from importlib import metadata

DISTRIBUTION = "go2-wbc"


def version_text() -> str:
    """``go2-wbc 0.1.0 (BSD-3-Clause; https://...)``, or says the package is not installed."""
    # What pip installed (a .dist-info), before any egg-info a build left in the checkout,
    # which an editable install puts on sys.path too and which may be stale.
    found = sorted(metadata.distributions(name=DISTRIBUTION),
                   key=lambda dist: not str(getattr(dist, "_path", "")).endswith(".dist-info"))
    if not found:
        return f"{DISTRIBUTION}: version unknown (run from a checkout without 'pip install')"
    meta = found[0].metadata
    urls = dict(entry.split(", ", 1) for entry in meta.get_all("Project-URL") or ())
    details = [meta.get("License-Expression") or meta.get("License") or "licence unknown"]
    if "Source" in urls:
        details.append(urls["Source"])
    return f"{DISTRIBUTION} {meta['Version']} ({'; '.join(details)})"
