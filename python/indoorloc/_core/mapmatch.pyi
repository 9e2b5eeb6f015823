# Stubs of indoorloc._core.mapmatch (no bindings yet).
