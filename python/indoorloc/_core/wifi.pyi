# Stubs of indoorloc._core.wifi (no bindings yet).
