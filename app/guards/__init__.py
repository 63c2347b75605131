"""The page's gate and guards: who may open the websocket, what a message, a GUI update or an upload may carry, and a server that outlives a hostile client."""
