"""The paper's experiments (Section V) rerun with our tools: results as frozen records, no drawing.

:mod:`~lfdfuse.evaluate.paper.records` holds the records and the pure measures on them;
:mod:`~lfdfuse.evaluate.paper.experiments` demonstrates, learns (:mod:`lfdfuse.learn`) and runs;
:mod:`~lfdfuse.evaluate.paper.suite` sequences every experiment into one
:class:`~lfdfuse.evaluate.paper.records.PaperResults`; :mod:`~lfdfuse.evaluate.paper.compare`
sets it beside the paper's claims. :mod:`lfdfuse.viz.report` draws and writes it.
"""
