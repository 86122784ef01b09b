"""The reduced-order model, part by part (docs/model.md §5–§9); :mod:`drillstring.dynamics.rom` gathers its public
names."""
