# Stubs of indoorloc._core.network (no bindings yet).
