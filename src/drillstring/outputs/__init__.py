"""The outputs: figures (Matplotlib, no physics), one module per kind of result; :mod:`drillstring.plots` offers
those of runs, studies, maps and sensitivity runs under one name. :mod:`~drillstring.outputs.canvas` holds what
every figure shares (the Agg canvas, the atomic PNG file, the axes' titles and display units)."""
