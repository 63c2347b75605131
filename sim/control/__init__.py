"""Take-off control: the controllers' laws and their best gains from the frequency domain."""
