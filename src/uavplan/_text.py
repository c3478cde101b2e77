"""Text helpers shared by the registries and the command line (no heavy imports)."""

from __future__ import annotations


def first_sentence(doc: str) -> str:
    """A docstring's first sentence on one line (up to the first full stop followed by a space
    or the end of its paragraph), without "(see the module docstring)" remarks."""
    import re

    para = " ".join(doc.strip().split("\n\n")[0].split())
    # a full stop ends the sentence unless it ends an abbreviation (Alg. 1, Sect. 5, e.g. ...)
    end = re.search(r"(?<!\bAlg)(?<!\bAlgs)(?<!\bSect)(?<!\bEq)(?<!\bEqs)(?<!\bFig)(?<!\bFigs)"
                    r"(?<!\be\.g)(?<!\bi\.e)(?<!\bvs)\.(\s|$)", para)  # fmt: skip
    text = para if end is None else para[: end.start() + 1]
    return text.replace(" (see the module docstring)", "").replace("; see the module docstring", "")
