"""Engine adapters (private): one package per engine, each importing its engine lazily."""
