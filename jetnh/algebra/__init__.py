"""The algebra layer: expressions as shared graphs (``dag``), linear algebra on them
(``linalg``), the zero tests (``zero``), shared display forms (``shared``), singular sets
(``singular``) and ansatz spaces (``ansatz``).  It knows nothing of jets."""
