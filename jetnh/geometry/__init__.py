"""The geometry layer: the jet space J^k M (``jet``), vector fields and their
prolongations (``fields``), differential forms (``forms``) and the Frobenius test
(``frobenius``)."""
