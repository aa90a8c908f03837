"""Live plots of topic fields, where the nodes run: a topic's numeric fields read by dotted
path (fields.py), sampled on a thread of their own per topic (sampler.py), folded into
buckets that keep min, max and last (buckets.py), and streamed to each client that asked
(streams.py: the session requests `plot`, `plot_stop`, `plot_fields`)."""
