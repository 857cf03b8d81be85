"""What every Drake workcell shares: model data (`models`), the offline parser (`parsing`),
port messages (`messages`), the BT executor system (`executor`), the chunked runner
(`runner`) and Meshcat views and recordings (`recording`)."""
