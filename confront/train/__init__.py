"""confront.train: a config's learner trained on a battle backend into a run folder (``factory.train_run``)."""
