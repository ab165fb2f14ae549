"""Machine-checked reproduction of Zhao, Guo, Liu, Liu, Acta Phys. Sin. 57 (2008).

``python -m papers.zhao2008`` (or ``jetnh reproduce``) writes ``results.json`` and
``report.md`` beside this file.
"""
