"""The live ROS graph as the inspector's requests read it: topics and their endpoints
(topic_graph.py), rates, echo and QoS problems streamed per client, and the Services and
Params tabs' requests (graph_requests.py)."""
