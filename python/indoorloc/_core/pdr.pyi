# Stubs of indoorloc._core.pdr (no bindings yet).
