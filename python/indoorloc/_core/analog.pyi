# Stubs of indoorloc._core.analog (no bindings yet).
